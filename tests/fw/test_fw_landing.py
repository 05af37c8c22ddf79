import math

import pytest

from stack.fw.landing import Landing, LandingParams, LandingSlope
from stack.params import catalogue

DEFAULTS = LandingParams.from_params({n: catalogue.get(n).default for n in LandingParams.PARAM_NAMES})
TAN5 = math.tan(math.radians(5.0))
# FW_LND_FLALT 3 m, FW_LND_HVIRT 10 m: H0 = 13, d1 = 3/tan 5°, c = H0·d1/3, L = c·ln(13/10).
D1 = 3.0 / TAN5
C = 13.0 * D1 / 3.0
L = C * math.log(13.0 / 10.0)
LAND = (0.0, 0.0)
PREVIOUS = (-500.0, 0.0)  # approaching northbound


def test_parameters():
    assert DEFAULTS.throttle_limit_altitude == pytest.approx(0.66 * 3.0)  # FW_LND_TLALT −1
    assert DEFAULTS.airspeed == pytest.approx(1.3 * 10.0)
    assert (DEFAULTS.flare_pitch_min, DEFAULTS.flare_pitch_max) == pytest.approx(
        (math.radians(2.5), math.radians(15.0))
    )


def test_slope_and_flare_geometry():
    slope = LandingSlope(math.radians(5.0), 3.0, 10.0)
    assert slope.flare_length == pytest.approx(L)
    assert slope.horizontal_slope_displacement == pytest.approx(L - D1)
    assert slope.slope_altitude(100.0) == pytest.approx((100.0 - (L - D1)) * TAN5)
    assert slope.slope_altitude(300.0) == pytest.approx(25.8, abs=0.05)
    assert slope.slope_distance(slope.slope_altitude(250.0)) == pytest.approx(250.0)
    # The flare leaves the slope at its start, at the flare altitude and tangent to it, and touches down
    # on the landing point.
    assert slope.slope_altitude(L) == pytest.approx(3.0)
    assert slope.flare_altitude_at(L) == pytest.approx(3.0)
    assert slope.flare_altitude_at(2.0 * L) == pytest.approx(3.0)
    assert slope.flare_altitude_at(0.0) == pytest.approx(0.0, abs=1e-12)
    step = 1e-4
    assert (slope.flare_altitude_at(L) - slope.flare_altitude_at(L - step)) / step == pytest.approx(TAN5, rel=1e-3)
    assert slope.flare_altitude_at(L / 2.0) == pytest.approx(13.0 * math.exp(-L / 2.0 / C) - 10.0)


def update(landing, north, altitude, yaw=0.0):
    return landing.update((north, 0.0), altitude, LAND, 0.0, yaw, PREVIOUS, 30.0)


def test_approach_holds_altitude_then_captures_the_slope():
    landing = Landing(DEFAULTS)
    sp = update(landing, -500.0, 30.0)  # below the slope (43 m here): hold the previous waypoint's altitude
    assert sp.altitude_sp == 30.0 and not sp.on_slope and not sp.flaring
    assert sp.airspeed_sp == pytest.approx(13.0)
    assert math.isnan(sp.pitch_min) and math.isnan(sp.pitch_max)
    assert sp.track_a == PREVIOUS and sp.track_b == pytest.approx((1000.0, 0.0))
    assert sp.target_bearing == 0.0 and not sp.heading_hold and sp.roll_limit == math.inf
    sp = update(landing, -300.0, 30.0)  # above the slope: follow it down
    assert sp.on_slope and sp.altitude_sp == pytest.approx((300.0 - (L - D1)) * TAN5)
    sp = update(landing, -200.0, 5.0)  # below it again, but captured
    assert sp.on_slope and sp.altitude_sp == pytest.approx((200.0 - (L - D1)) * TAN5)


def test_flare_pitch_limits_throttle_limit_and_heading_hold():
    landing = Landing(DEFAULTS)
    update(landing, -300.0, 30.0)
    sp = update(landing, -30.0, 2.9)
    assert sp.flaring and sp.altitude_sp == pytest.approx(13.0 * math.exp(-(L - 30.0) / C) - 10.0)
    assert (sp.pitch_min, sp.pitch_max) == (DEFAULTS.flare_pitch_min, DEFAULTS.flare_pitch_max)
    assert not sp.throttle_limited  # above 2/3 of the flare altitude
    assert not sp.heading_hold  # from the next step on, as in PX4
    sp = update(landing, -28.0, 2.5, yaw=0.3)
    assert sp.heading_hold and sp.target_bearing == 0.0 and sp.roll_limit == pytest.approx(math.radians(10.0))
    sp = update(landing, -20.0, 1.9)
    assert sp.throttle_limited
    sp = update(landing, -10.0, 3.5)  # a bounce does not end the flare
    assert sp.flaring and sp.throttle_limited
    sp = update(landing, 5.0, 0.5)  # past the landing point, still flying: the curve goes on below the runway
    assert sp.altitude_sp == pytest.approx(13.0 * math.exp(-(L + 5.0) / C) - 10.0) and sp.altitude_sp < -0.3
    landing.reset()
    assert not update(landing, -300.0, 30.0).flaring


def test_an_idle_flare_ends_at_the_runway_height():
    values = {n: catalogue.get(n).default for n in LandingParams.PARAM_NAMES} | {"FW_THR_LND_MAX": 0.0}
    landing = Landing(LandingParams.from_params(values))
    update(landing, -300.0, 30.0)
    assert update(landing, -20.0, 1.9).throttle_limited
    assert update(landing, 5.0, 0.5).altitude_sp == 0.0  # past the point: nothing holds it up, it settles


def test_heading_hold_from_the_hold_distance():
    landing = Landing(DEFAULTS)
    assert not update(landing, -16.0, 4.0).heading_hold
    assert update(landing, -14.0, 4.0).heading_hold


def test_a_flare_curve_never_rises_again():
    landing = Landing(DEFAULTS)
    low = update(landing, -20.0, 2.0).altitude_sp
    assert update(landing, -25.0, 1.0).altitude_sp == low  # farther from the point: the curve would rise
    assert update(landing, -10.0, 0.5).altitude_sp < low


def test_without_a_previous_waypoint_the_line_is_the_bearing_to_the_landing_point():
    landing = Landing(DEFAULTS)
    sp = landing.update((0.0, -100.0), 20.0, LAND, 0.0, 0.0)
    assert sp.target_bearing == pytest.approx(0.5 * math.pi)
    assert sp.track_a == (0.0, -100.0) and sp.track_b == pytest.approx((0.0, 1000.0))
    assert sp.altitude_sp == pytest.approx((100.0 - (L - D1)) * TAN5)  # above the slope: on it
