import dataclasses
import math

import pytest

from stack.fw.l1_guidance import L1Guidance
from stack.fw.npfg import NPFG, NpfgParams
from stack.mathlib.scalar import CONSTANTS_ONE_G as G

DEFAULTS = NpfgParams()
A = (0.0, 0.0)
B = (1000.0, 0.0)  # a northbound leg
P_GAIN = 4.0 * math.pi * 0.7 / 10.0  # nominal period 10 s, damping 0.7
TIME_CONSTANT = 10.0 * 0.7


def test_defaults_come_from_the_catalogue():
    assert (DEFAULTS.fw_npfg_period, DEFAULTS.fw_npfg_damping, DEFAULTS.fw_npfg_sw_dst_mlt) == (10.0, 0.7, 0.32)
    assert DEFAULTS.fw_r_lim == 50.0
    assert (DEFAULTS.fw_airspd_trim, DEFAULTS.fw_airspd_max, DEFAULTS.fw_gnd_spd_min) == (15.0, 20.0, 5.0)


def test_on_the_track_heading_along_it_no_lateral_acceleration():
    npfg = NPFG(DEFAULTS)
    a = npfg.navigate_waypoints(A, B, (100.0, 0.0), (15.0, 0.0))
    assert a == pytest.approx(0.0, abs=1e-12) and npfg.roll_setpoint == pytest.approx(0.0, abs=1e-12)
    assert npfg.crosstrack_error == 0.0
    assert npfg.nav_bearing == pytest.approx(0.0, abs=1e-12) and npfg.target_bearing == 0.0
    assert npfg.airspeed_reference == pytest.approx(15.0)
    assert npfg.track_error_bound == pytest.approx(15.0 * TIME_CONSTANT)
    assert npfg.switch_distance(100.0) == pytest.approx(0.32 * 15.0 * TIME_CONSTANT)
    assert npfg.switch_distance(10.0) == 10.0


def test_offset_from_the_track_turns_toward_it():
    # 5 m right (east) of the track at 15 m/s: bound 15·7 = 105 m, look-ahead (π/2)·(1 − 5/105)² from
    # the track normal; a = k·(V × V_ref)/|V_ref| = −k·15·cos(look-ahead).
    npfg = NPFG(DEFAULTS)
    a = npfg.navigate_waypoints(A, B, (100.0, 5.0), (15.0, 0.0))
    look_ahead = 0.5 * math.pi * (1.0 - 5.0 / 105.0) ** 2
    assert npfg.crosstrack_error == pytest.approx(5.0)
    assert a == pytest.approx(-P_GAIN * 15.0 * math.cos(look_ahead))
    assert npfg.roll_setpoint == pytest.approx(math.atan(a / G))
    assert npfg.nav_bearing == pytest.approx(-(0.5 * math.pi - look_ahead))
    assert npfg.navigate_waypoints(A, B, (100.0, -5.0), (15.0, 0.0)) == pytest.approx(-a)


def test_far_from_the_track_it_heads_straight_for_it_with_the_full_turn():
    npfg = NPFG(DEFAULTS)
    a = npfg.navigate_waypoints(A, B, (100.0, 500.0), (15.0, 0.0))
    assert npfg.nav_bearing == pytest.approx(-0.5 * math.pi)
    assert a == pytest.approx(-P_GAIN * 15.0)


def test_before_the_first_waypoint_it_flies_to_it():
    npfg = NPFG(DEFAULTS)
    npfg.navigate_waypoints(A, B, (-300.0, 10.0), (15.0, 0.0))
    assert npfg.nav_bearing == pytest.approx(math.atan2(-10.0, 300.0))


def test_past_the_end_of_the_leg_it_turns_back_to_it():
    # Overflown 200 m north of B and 30 m east of the line, still flying north: back to B, not on along the line.
    npfg = NPFG(DEFAULTS)
    a = npfg.navigate_waypoints(A, B, (1200.0, 30.0), (15.0, 0.0))
    assert npfg.nav_bearing == pytest.approx(math.atan2(-30.0, -200.0))
    assert abs(a) == pytest.approx(P_GAIN * 15.0)
    # Short of B it follows the line.
    npfg.navigate_waypoints(A, B, (999.0, 0.0), (15.0, 0.0))
    assert npfg.nav_bearing == pytest.approx(0.0, abs=1e-12)


def test_on_the_loiter_circle_the_centripetal_acceleration():
    npfg = NPFG(DEFAULTS)
    # North of the centre, flying east: clockwise.
    a = npfg.navigate_loiter((0.0, 0.0), (80.0, 0.0), 80.0, 1, (0.0, 15.0))
    assert a == pytest.approx(15.0**2 / 80.0)
    assert npfg.circle_mode and npfg.crosstrack_error == pytest.approx(0.0)
    a = npfg.navigate_loiter((0.0, 0.0), (80.0, 0.0), 80.0, -1, (0.0, -15.0))
    assert a == pytest.approx(-(15.0**2) / 80.0)
    npfg.navigate_loiter((0.0, 0.0), (300.0, 0.0), 80.0, 1, (0.0, 15.0))
    assert npfg.crosstrack_error == pytest.approx(220.0)
    assert not npfg.circle_mode


def test_heading_and_level_flight():
    npfg = NPFG(DEFAULTS)
    assert npfg.navigate_heading(0.3, 0.3, (15.0 * math.cos(0.3), 15.0 * math.sin(0.3))) == pytest.approx(0.0)
    assert npfg.navigate_heading(0.8, 0.3, (15.0 * math.cos(0.3), 15.0 * math.sin(0.3))) > 0.0
    assert npfg.navigate_level_flight(1.0) == 0.0 and npfg.nav_bearing == 1.0


def test_roll_limit_and_slew_rate():
    npfg = NPFG(DEFAULTS)
    npfg.navigate_waypoints(A, B, (100.0, 500.0), (15.0, 0.0), dt=0.1)
    assert npfg.roll_setpoint == pytest.approx(-math.radians(9.0))  # 90 °/s for 0.1 s
    limited = NPFG(dataclasses.replace(DEFAULTS, fw_r_lim=5.0, fw_l1_r_slew_max=0.0))
    limited.navigate_waypoints(A, B, (100.0, 500.0), (15.0, 0.0), dt=0.1)
    assert limited.roll_setpoint == pytest.approx(-math.radians(5.0))


def test_bearing_feasibility_and_airspeed_reference_in_excess_cross_wind():
    # 18 m/s of wind across a track flown at 15 m/s: infeasible at the nominal airspeed. The reference
    # rises so that the wind triangle closes with the minimum forward ground speed of 5 m/s.
    npfg = NPFG(DEFAULTS)
    wind = (0.0, 18.0)
    npfg.navigate_waypoints(A, B, (100.0, 0.0), (0.0, 18.0 + 15.0), wind=wind)
    assert npfg.bearing_feasibility == 0.0
    assert npfg.airspeed_reference == pytest.approx(math.hypot(5.0, 18.0))
    reference = npfg.heading_reference
    ground = (npfg.airspeed_reference * math.cos(reference), npfg.airspeed_reference * math.sin(reference) + 18.0)
    assert ground == pytest.approx((5.0, 0.0), abs=1e-9)
    # Feasible once the airspeed exceeds the cross wind by the 1.5 m/s buffer (here 20.6 m/s).
    npfg.navigate_waypoints(A, B, (100.0, 0.0), (10.0, 0.0), wind=wind)
    assert npfg.bearing_feasibility == 1.0


def simulate(guidance, path, wind=(0.0, 0.0), position=(0.0, 60.0), heading=0.0, duration=120.0, use_wind=True):
    """A point mass at the commanded airspeed (first order, 2 s, at most 20 m/s) banking after the roll
    setpoint (first order, 0.5 s): the positions, ground velocities and cross-track errors."""
    dt = 0.02
    x, y = position
    psi, roll, airspeed = heading, 0.0, 15.0
    trace = []
    for _ in range(int(duration / dt)):
        ground = (airspeed * math.cos(psi) + wind[0], airspeed * math.sin(psi) + wind[1])
        kw = {"wind": wind} if use_wind else {}
        path(guidance, (x, y), ground, dt, kw)
        reference = getattr(guidance, "airspeed_reference", 15.0)
        airspeed += (min(reference, 20.0) - airspeed) * dt / 2.0
        roll += (guidance.roll_setpoint - roll) * dt / 0.5
        psi += G * math.tan(roll) / airspeed * dt
        x, y = x + ground[0] * dt, y + ground[1] * dt
        trace.append(((x, y), ground, guidance.crosstrack_error))
    return trace


def line(guidance, position, ground, dt, kw):
    """A leg long enough not to be passed within a simulation (past its end the guidance turns back)."""
    guidance.navigate_waypoints(A, (5000.0, 0.0), position, ground, dt, **kw)


def loiter(guidance, position, ground, dt, kw):
    guidance.navigate_loiter((0.0, 0.0), position, 80.0, 1, ground, dt, **kw)


@pytest.mark.parametrize("wind", [(0.0, 0.0), (0.0, 8.0), (-8.0, 0.0)])
def test_converges_onto_a_line_and_stays(wind):
    trace = simulate(NPFG(DEFAULTS), line, wind)
    assert max(abs(e) for _, _, e in trace[len(trace) // 2 :]) < 0.05


@pytest.mark.parametrize("wind", [(0.0, 0.0), (8.0, 0.0)])
def test_loiter_radius_in_wind(wind):
    trace = simulate(NPFG(DEFAULTS), loiter, wind, position=(300.0, 0.0), duration=240.0)
    assert max(abs(e) for _, _, e in trace[len(trace) // 2 :]) < 2.0


def test_in_a_cross_wind_stronger_than_the_airspeed_it_holds_the_track():
    # 18 m/s across the track, nominal airspeed 15: the airspeed goes up (max 20), the track holds.
    trace = simulate(NPFG(DEFAULTS), line, (0.0, 18.0), position=(0.0, 0.0))
    (x, _), ground, error = trace[-1]
    assert abs(error) < 1.0 and ground[0] > 4.0 and x > 400.0


def test_in_a_head_wind_beyond_the_maximum_airspeed_it_does_not_run_away():
    # 25 m/s from ahead, 20 m/s at most: it loses ground at ≈ 5 m/s but keeps its nose in the wind, on the
    # track, instead of turning away downwind.
    npfg = NPFG(DEFAULTS)
    trace = simulate(npfg, line, (-25.0, 0.0), position=(0.0, 0.0))
    (x, y), ground, _ = trace[-1]
    assert ground[0] == pytest.approx(-5.0, abs=0.1) and abs(y) < 1.0
    assert math.cos(npfg.heading_reference) > 0.99
    assert x > -5.5 * 120.0


def test_excess_head_wind_regulation_flies_into_the_wind():
    # No ground speed keeping: between the nominal and the maximum airspeed the reference is the wind speed,
    # nose into the wind (zero ground speed), not downwind.
    params = dataclasses.replace(DEFAULTS, fw_npfg_en_min_gsp=0, fw_npfg_track_keep=0)
    npfg = NPFG(params)
    npfg.navigate_waypoints(A, B, (100.0, 0.0), (-3.0, 0.0), wind=(-18.0, 0.0))
    assert npfg.airspeed_reference == pytest.approx(18.0)
    assert npfg.heading_reference == pytest.approx(0.0)
    trace = simulate(npfg, line, (-18.0, 0.0), position=(0.0, 0.0), duration=60.0)
    assert trace[-1][1][0] == pytest.approx(0.0, abs=0.1)


def test_mirrors_the_l1_interface():
    npfg, l1 = NPFG(DEFAULTS), L1Guidance()
    for guidance in (npfg, l1):
        guidance.navigate_waypoints(A, B, (100.0, 5.0), (15.0, 0.0), 0.02)
        guidance.navigate_loiter((0.0, 0.0), (80.0, 0.0), 80.0, 1, (0.0, 15.0), 0.02)
        guidance.navigate_heading(0.3, 0.0, (15.0, 0.0), 0.02)
        guidance.navigate_level_flight(0.0, 0.02)
        assert guidance.switch_distance(10.0) <= 10.0
        for attribute in ("lateral_acceleration", "roll_setpoint", "nav_bearing", "target_bearing", "bearing_error"):
            assert math.isfinite(getattr(guidance, attribute))
        assert guidance.lateral_acceleration_ne == (0.0, 0.0)


def test_without_a_wind_estimate_it_flies_as_in_calm_air():
    npfg = NPFG(DEFAULTS)
    a = npfg.navigate_waypoints(A, B, (100.0, 5.0), (15.0, 0.0), wind=(math.nan, math.nan))
    assert a == pytest.approx(NPFG(DEFAULTS).navigate_waypoints(A, B, (100.0, 5.0), (15.0, 0.0)))
