import math

import pytest

from stack.fw.landing import Landing, LandingParams
from stack.params import catalogue

DEFAULTS = LandingParams()
TAN5 = math.tan(math.radians(5.0))
LAND = (0.0, 0.0)
PREVIOUS = (-500.0, 0.0)  # approaching northbound, from 30 m
P_LIM_MIN, P_LIM_MAX = math.radians(-45.0), math.radians(45.0)  # FW_P_LIM_MIN/MAX


def update(landing, north, altitude, *, now=0.0, down_speed=1.0, throttle=0.5, yaw=0.0):
    return landing.update(
        (north, 0.0), altitude, LAND, 0.0, yaw, PREVIOUS, 30.0, now=now, down_speed=down_speed, throttle=throttle
    )


def flare(landing, t0=10.0, down_speed=1.2, throttle=0.4):
    """Approach at 5 m, then start the flare at t0 at 0.3 m."""
    update(landing, -60.0, 5.0, now=t0 - 1.0, down_speed=down_speed, throttle=throttle)
    return update(landing, -4.0, 0.3, now=t0, down_speed=down_speed, throttle=throttle)


def test_parameters_are_px4_v1_14s():
    assert DEFAULTS.fw_lnd_flalt == 0.5 and DEFAULTS.fw_lnd_fl_time == 1.0 and DEFAULTS.fw_lnd_fl_sink == 0.25
    assert DEFAULTS.fw_lnd_td_time == -1.0
    assert (DEFAULTS.fw_lnd_airspd_sc, DEFAULTS.fw_airspd_min) == (1.3, 10.0)
    assert (DEFAULTS.fw_lnd_fl_pmin, DEFAULTS.fw_lnd_fl_pmax) == (2.5, 15.0)
    assert (DEFAULTS.fw_p_lim_min, DEFAULTS.fw_p_lim_max) == pytest.approx(
        (math.degrees(P_LIM_MIN), math.degrees(P_LIM_MAX))
    )
    assert (DEFAULTS.fw_thr_max, DEFAULTS.fw_thr_idle) == (1.0, 0.0)
    for removed in ("FW_LND_HVIRT", "FW_LND_TLALT", "FW_THR_LND_MAX"):
        assert removed not in catalogue.CATALOGUE


def test_the_glide_slope_is_a_straight_line_to_the_landing_point_capped_at_the_entrance():
    landing = Landing(DEFAULTS)
    # Below the slope (26 m here): hold the entrance's height (the previous waypoint's 30 m) until it is captured.
    sp = update(landing, -300.0, 20.0)
    assert not sp.on_slope and not sp.flaring and sp.altitude_sp == 30.0
    assert math.isnan(sp.height_rate_sp) and math.isnan(sp.pitch_min) and math.isnan(sp.throttle_max)
    assert sp.airspeed_sp == pytest.approx(13.0)
    assert sp.track_a == PREVIOUS and sp.track_b == pytest.approx((1000.0, 0.0))
    assert sp.target_bearing == 0.0 and not sp.heading_hold and sp.roll_limit == math.inf
    # At or above it: follow it down, and keep following it once captured.
    sp = update(landing, -200.0, 20.0)
    assert sp.on_slope and sp.altitude_sp == pytest.approx(200.0 * TAN5)
    sp = update(landing, -150.0, 10.0)
    assert sp.on_slope and sp.altitude_sp == pytest.approx(150.0 * TAN5)
    # Far out the slope would be above the entrance: capped there.
    assert update(landing, -450.0, 35.0).altitude_sp == pytest.approx(30.0)
    # Still turning onto the line, abeam of its first 100 m: the slope is by the distance to the point (316 m).
    sp = Landing(DEFAULTS).update((-100.0, 300.0), 20.0, LAND, 0.0, 0.0, PREVIOUS, 30.0, now=0.0, down_speed=0.0)
    assert sp.altitude_sp == 30.0 and not sp.on_slope
    # Past the landing point the slope goes on below the runway.
    assert update(Landing(DEFAULTS), 10.0, 3.0, down_speed=0.0).altitude_sp == pytest.approx(-10.0 * TAN5)


def test_the_flare_starts_at_the_higher_of_the_flare_altitude_and_the_flare_time_times_the_sink_rate():
    # Sinking at 0.3 m/s: FW_LND_FLALT (0.5 m) decides.
    landing = Landing(DEFAULTS)
    assert not update(landing, -10.0, 0.55, down_speed=0.3).flaring
    assert update(landing, -9.0, 0.45, down_speed=0.3).flaring
    # Sinking at 2 m/s: 1 s before the runway, at 2 m.
    landing = Landing(DEFAULTS)
    assert not update(landing, -30.0, 2.05, down_speed=2.0).flaring
    assert update(landing, -29.0, 1.95, down_speed=2.0).flaring
    landing = Landing(LandingParams(fw_lnd_fl_time=2.0, fw_lnd_flalt=3.0))
    assert not update(landing, -30.0, 3.1, down_speed=1.0).flaring
    assert update(landing, -29.0, 2.9, down_speed=1.0).flaring


def test_the_flare_ramps_height_rate_pitch_limits_and_throttle_over_the_flare_time():
    landing = Landing(DEFAULTS)
    start = flare(landing, down_speed=1.2)
    # At its start: the sink rate it had, the controller's pitch limits, full throttle allowed, at least idle.
    assert start.flaring and math.isnan(start.altitude_sp)
    assert start.height_rate_sp == pytest.approx(-1.2)
    assert (start.pitch_min, start.pitch_max) == pytest.approx((P_LIM_MIN, P_LIM_MAX))
    assert (start.throttle_min, start.throttle_max) == (0.0, 1.0)
    # A quarter of the way: the ramp is √(1/4) = 1/2.
    sp = update(landing, -1.0, 0.2, now=10.25)
    assert sp.height_rate_sp == pytest.approx(0.5 * -0.25 + 0.5 * -1.2)
    assert sp.pitch_min == pytest.approx(0.5 * math.radians(2.5) + 0.5 * P_LIM_MIN)
    assert sp.pitch_max == pytest.approx(0.5 * math.radians(15.0) + 0.5 * P_LIM_MAX)
    assert sp.throttle_max == pytest.approx(0.5)
    # From FW_LND_FL_TIME on: the flare's sink rate and pitch limits, idle throttle.
    for now in (11.0, 13.0):
        sp = update(landing, 2.0, 0.1, now=now)
        assert sp.height_rate_sp == pytest.approx(-0.25)
        assert (sp.pitch_min, sp.pitch_max) == pytest.approx((math.radians(2.5), math.radians(15.0)))
        assert sp.throttle_max == pytest.approx(0.0)


def test_the_throttle_goes_to_idle_even_with_a_non_zero_idle():
    landing = Landing(LandingParams(fw_thr_idle=0.15, fw_thr_max=0.9))
    flare(landing)
    sp = update(landing, -1.0, 0.2, now=10.25)
    assert sp.throttle_min == 0.15 and sp.throttle_max == pytest.approx(0.5 * 0.15 + 0.5 * 0.9)
    assert update(landing, 2.0, 0.1, now=11.5).throttle_max == pytest.approx(0.15)


def test_the_sent_throttle_blends_from_the_flare_start_throttle_to_tecs_linearly():
    landing = Landing(DEFAULTS)
    flare(landing, throttle=0.4)
    assert landing.flare_throttle(0.1) == pytest.approx(0.4)
    update(landing, -1.0, 0.2, now=10.25)
    assert landing.flare_throttle(0.1) == pytest.approx(0.25 * 0.1 + 0.75 * 0.4)
    update(landing, 2.0, 0.1, now=11.0)
    assert landing.flare_throttle(0.1) == pytest.approx(0.1)
    # Without a throttle at its start, TECS' own.
    landing = Landing(DEFAULTS)
    flare(landing, throttle=math.nan)
    assert landing.flare_throttle(0.3) == 0.3


def test_the_flare_latches_until_reset():
    landing = Landing(DEFAULTS)
    flare(landing, down_speed=1.0)
    sp = update(landing, 1.0, 4.0, now=10.5, down_speed=-3.0)  # a bounce, climbing: still flaring, same ramp
    assert sp.flaring and sp.height_rate_sp == pytest.approx(math.sqrt(0.5) * -0.25 + (1.0 - math.sqrt(0.5)) * -1.0)
    assert update(landing, -200.0, 25.0).flaring  # nor does climbing back to the slope end it
    landing.reset()
    assert update(landing, -200.0, 25.0, now=20.0).on_slope


def test_the_touchdown_time_clamps_the_pitch_to_the_runway_pitch():
    landing = Landing(LandingParams(fw_lnd_td_time=2.0, rwto_psp=1.0))
    flare(landing)
    assert update(landing, 2.0, 0.1, now=12.0).pitch_min == pytest.approx(math.radians(2.5))
    sp = update(landing, 3.0, 0.05, now=12.25)  # half way through the 0.5 s clamp
    assert sp.pitch_min == pytest.approx(0.5 * math.radians(1.0) + 0.5 * math.radians(2.5))
    assert sp.pitch_max == pytest.approx(0.5 * math.radians(1.0) + 0.5 * math.radians(15.0))
    sp = update(landing, 4.0, 0.0, now=12.5)
    assert (sp.pitch_min, sp.pitch_max) == pytest.approx((math.radians(1.0), math.radians(1.0)))
    # It waits for the flare to have ramped in: at least FW_LND_FL_TIME after its start.
    landing = Landing(LandingParams(fw_lnd_td_time=0.5, fw_lnd_fl_time=2.0, rwto_psp=1.0))
    flare(landing)
    assert update(landing, 2.0, 0.1, now=12.0).pitch_min == pytest.approx(math.radians(2.5))


def test_heading_hold_from_the_hold_distance_or_the_flare():
    landing = Landing(DEFAULTS)
    assert not update(landing, -16.0, 4.0).heading_hold
    sp = update(landing, -14.0, 4.0, yaw=0.3)
    assert sp.heading_hold and sp.target_bearing == 0.0 and sp.roll_limit == pytest.approx(math.radians(10.0))
    landing = Landing(LandingParams(fw_lnd_hhdist=0.0))
    assert not flare(landing).heading_hold
    landing = Landing(DEFAULTS)
    update(landing, -60.0, 5.0)
    assert update(landing, -50.0, 0.3).flaring
    assert update(landing, -49.0, 0.2).heading_hold  # from the step after the flare's start, as in PX4 v1.13


def test_without_a_previous_waypoint_the_line_is_the_bearing_to_the_landing_point():
    landing = Landing(DEFAULTS)
    sp = landing.update((0.0, -300.0), 20.0, LAND, 0.0, 0.0, now=0.0, down_speed=0.0)
    assert sp.target_bearing == pytest.approx(0.5 * math.pi)
    assert sp.track_a == (0.0, -300.0) and sp.track_b == pytest.approx((0.0, 1000.0))
    # The entrance is where the landing began: the slope (26 m here) is capped at its 20 m.
    assert sp.altitude_sp == 20.0 and sp.on_slope
    assert landing.update((0.0, -250.0), 22.0, LAND, 0.0, 0.0, now=1.0, down_speed=0.0).altitude_sp == 20.0
    sp = landing.update((0.0, -100.0), 20.0, LAND, 0.0, 0.0, now=2.0, down_speed=0.0)
    assert sp.altitude_sp == pytest.approx(100.0 * TAN5)
