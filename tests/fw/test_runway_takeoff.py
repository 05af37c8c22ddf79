import dataclasses
import math

import pytest

from stack.fw.runway_takeoff import RunwayTakeoff, RunwayTakeoffParams, RunwayTakeoffState

DEFAULTS = RunwayTakeoffParams()
S = RunwayTakeoffState
NAV_ROLL = math.radians(40.0)
NAV_YAW = 1.2
TECS_PITCH = math.radians(12.0)
TECS_THROTTLE = 0.8


def test_parameters():
    assert (DEFAULTS.rwto_airspd_scl, DEFAULTS.fw_airspd_min) == (1.3, 10.0)
    assert (DEFAULTS.rwto_ramp_time, DEFAULTS.rwto_nav_alt, DEFAULTS.fw_clmbout_diff) == (2.0, 5.0, 10.0)
    assert DEFAULTS.rwto_max_pitch == 20.0
    assert DEFAULTS.rwto_max_roll == 25.0


def fly(params):
    """A scripted takeoff at 50 Hz: 2 m/s² along the runway (north), lift-off at 8 s, then climbing at 2 m/s.
    Returns (time, state, throttle, pitch, roll, yaw, wheel steering, reset integrators) rows."""
    takeoff = RunwayTakeoff(params)
    takeoff.init(0, 0.5, (0.0, 0.0))
    rows = []
    for i in range(1, 15 * 50 + 1):
        t = i * 0.02
        time_us = round(t * 1e6)
        airspeed = 2.0 * t
        altitude = max(0.0, 2.0 * (t - 8.0))
        state = takeoff.update(time_us, airspeed, altitude, (t * t, 0.0))
        rows.append(
            (
                t,
                state,
                takeoff.throttle(time_us, TECS_THROTTLE),
                takeoff.pitch(TECS_PITCH),
                takeoff.roll(NAV_ROLL),
                takeoff.yaw(NAV_YAW),
                takeoff.wheel_steering,
                takeoff.reset_integrators,
            )
        )
    return takeoff, rows


def first(rows, state):
    return next(row for row in rows if row[1] == state)


def test_the_state_sequence_against_a_scripted_takeoff():
    takeoff, rows = fly(DEFAULTS)
    states = [row[1] for row in rows]
    assert states == sorted(states)  # never back
    # Ramp for 2 s; rotation at 1.3·10 m/s (6.5 s); navigation above 5 m (10.5 s); flying above 10 m (13 s).
    assert first(rows, S.CLAMPED_TO_RUNWAY)[0] == pytest.approx(2.02)
    assert first(rows, S.TAKEOFF)[0] == pytest.approx(6.52)
    assert first(rows, S.CLIMBOUT)[0] == pytest.approx(10.52)
    assert first(rows, S.FLY)[0] == pytest.approx(13.02)
    assert not takeoff.climbout
    # Navigation starts from where the climb-out began (RWTO_HDG 0).
    assert takeoff.start_position == (10.52**2, 0.0)


def test_the_outputs_of_each_state():
    _, rows = fly(DEFAULTS)
    at_1s = next(row for row in rows if row[0] == pytest.approx(1.0))
    assert at_1s[1] == S.THROTTLE_RAMP
    assert at_1s[2] == pytest.approx(0.5)  # half way up the 2 s ramp to RWTO_MAX_THR 1
    assert at_1s[3:] == (0.0, 0.0, 0.5, True, True)  # RWTO_PSP, wings level, initial heading on the wheel
    clamped = first(rows, S.CLAMPED_TO_RUNWAY)
    assert clamped[2:] == (1.0, 0.0, 0.0, 0.5, True, True)
    rotating = first(rows, S.TAKEOFF)
    assert rotating[2:] == (TECS_THROTTLE, TECS_PITCH, 0.0, 0.5, True, False)
    climbing = first(rows, S.CLIMBOUT)
    assert climbing[2:] == (TECS_THROTTLE, TECS_PITCH, pytest.approx(math.radians(25.0)), NAV_YAW, False, False)
    flying = first(rows, S.FLY)
    assert flying[4] == NAV_ROLL


def test_pitch_limits_until_flying():
    takeoff = RunwayTakeoff(DEFAULTS)
    takeoff.init(0, 0.0, (0.0, 0.0))
    assert takeoff.max_pitch(0.7) == pytest.approx(math.radians(20.0))
    assert takeoff.min_pitch(0.17, -0.5) == 0.17
    no_limit = RunwayTakeoff(dataclasses.replace(DEFAULTS, rwto_max_pitch=0.0))
    no_limit.init(0, 0.0, (0.0, 0.0))
    assert no_limit.max_pitch(0.7) == 0.7
    takeoff.state = S.FLY
    assert takeoff.max_pitch(0.7) == 0.7 and takeoff.min_pitch(0.17, -0.5) == -0.5


def test_a_fast_acceleration_ends_the_ramp_early():
    takeoff = RunwayTakeoff(DEFAULTS)
    takeoff.init(0, 0.0, (0.0, 0.0))
    assert takeoff.update(500_000, 0.9 * 13.0 - 0.1, 0.0, (0.0, 0.0)) == S.THROTTLE_RAMP
    assert takeoff.update(520_000, 0.9 * 13.0 + 0.1, 0.0, (0.0, 0.0)) == S.CLAMPED_TO_RUNWAY


def test_heading_to_the_waypoint_on_the_ground():
    takeoff = RunwayTakeoff(dataclasses.replace(DEFAULTS, rwto_hdg=1))
    takeoff.init(0, 0.5, (0.0, 0.0))
    assert takeoff.yaw(NAV_YAW) == NAV_YAW and takeoff.wheel_steering
    takeoff.update(3_000_000, 14.0, 6.0, (50.0, 0.0))
    takeoff.update(3_020_000, 14.0, 6.0, (50.0, 0.0))
    takeoff.update(3_040_000, 14.0, 6.0, (51.0, 0.0))
    assert takeoff.state == S.CLIMBOUT
    assert takeoff.start_position == (0.0, 0.0)  # the runway's start stays the line's start
