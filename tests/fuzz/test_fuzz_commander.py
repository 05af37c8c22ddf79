"""Fuzz the commander's inputs: any command, any estimate or sensor input, any takeoff state. Nothing raises; a
command is answered (or, addressed elsewhere, ignored), a refusal changes nothing, and what an accepted one
asks the navigator to fly is finite (NaN only where it means "keep")."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from stack.commander import commands as C
from stack.commander.failsafe import Failsafe, FailsafeConditions
from stack.commander.health import CommanderInputs
from stack.commander.land_detector import LandDetectorInputs, MulticopterLandDetector, takeoff_state
from stack.commander.modes import MODES, Requirement
from stack.commander.state_machine import SUPPORTED_COMMANDS, Commander
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import VehicleCommand
from stack.msg.system import VehicleCommandAck as ACK
from tests.commander.helpers import make_clock
from tests.fuzz.strategies import FUZZ, all_finite, any_int, finite_or_nan, nasty_float, quat, vec3

CMD = VehicleCommand
command_ids = st.one_of(
    st.sampled_from(sorted(SUPPORTED_COMMANDS)), st.integers(-(2**31), 2**31)
)
commands = st.builds(
    CMD,
    param1=nasty_float,
    param2=nasty_float,
    param3=nasty_float,
    param4=nasty_float,
    param5=nasty_float,
    param6=nasty_float,
    param7=nasty_float,
    command=command_ids,
    target_system=st.one_of(st.just(1), st.just(0), any_int),
    target_component=st.one_of(st.just(1), st.just(0), any_int),
    source_system=st.integers(0, 255),
    source_component=st.integers(0, 255),
)


def _snapshot(out):
    s = out.vehicle_status
    return (s.arming_state, s.nav_state, s.nav_state_user_intention, out.home, out.navigation)


def _check_navigation(nav) -> None:
    assert math.isfinite(nav.takeoff_altitude)
    assert finite_or_nan(nav.takeoff_yaw)
    if nav.reposition is not None:
        assert all_finite(nav.reposition[:3])
        assert finite_or_nan(nav.reposition[3])
    assert finite_or_nan(nav.reposition_speed)


@FUZZ
@given(cmd=commands, flying=st.booleans(), sticks=st.booleans())
def test_any_command_is_answered_and_a_refusal_changes_nothing(cmd, flying, sticks):
    clock = make_clock(GF_MAX_HOR_DIST=100.0)
    clock.sticks = sticks
    if flying:
        clock.send(C.takeoff_command(5.0))
        clock.fly_to((0.0, 0.0, -5.0))
    before = _snapshot(clock.step())
    ack = clock.send(cmd)
    out = clock.step()
    if ack is None:
        assert not clock.commander.addressed_to_me(cmd)
        assert _snapshot(out) == before
        return
    assert ack.command == cmd.command
    if ack.result != ACK.VEHICLE_CMD_RESULT_ACCEPTED:
        assert ack.reason
        assert _snapshot(out)[:3] == before[:3] and out.navigation == before[4]
    _check_navigation(out.navigation)


local_positions = st.builds(
    VehicleLocalPosition,
    timestamp=any_int,
    xy_valid=st.booleans(),
    z_valid=st.booleans(),
    v_xy_valid=st.booleans(),
    v_z_valid=st.booleans(),
    x=nasty_float,
    y=nasty_float,
    z=nasty_float,
    vx=nasty_float,
    vy=nasty_float,
    vz=nasty_float,
    heading=nasty_float,
    eph=nasty_float,
    epv=nasty_float,
    ref_lat=nasty_float,
    ref_lon=nasty_float,
    ref_alt=nasty_float,
)
inputs = st.builds(
    CommanderInputs,
    attitude_timestamp_us=any_int,
    attitude_q=quat,
    angular_velocity_timestamp_us=any_int,
    local_position=st.one_of(st.none(), local_positions),
    gyro_timestamp_us=any_int,
    accel_timestamp_us=any_int,
    baro_timestamp_us=any_int,
    mag_timestamp_us=any_int,
    gps_timestamp_us=any_int,
    gps_fix_type=any_int,
    landed=st.booleans(),
    maybe_landed=st.booleans(),
    battery_warning=any_int,
    last_gcs_heartbeat_us=any_int,
    last_manual_control_us=any_int,
    manual_control_valid=st.booleans(),
    mission_count=any_int,
    mission_finished=st.booleans(),
)


@FUZZ
@given(steps=st.lists(st.tuples(inputs, st.one_of(st.none(), commands)), min_size=1, max_size=4))
def test_any_inputs_and_commands_keep_the_commander_running(steps):
    commander = Commander({"GF_MAX_HOR_DIST": 50.0, "GF_MAX_VER_DIST": 30.0})
    now = 1_000_000
    for inp, cmd in steps:
        now += 10_000
        if cmd is not None:
            commander.set_inputs(now, inp)
            commander.handle_command(cmd, now)
        out = commander.update(now, inp)
        assert out.vehicle_status.nav_state in MODES
        _check_navigation(out.navigation)


@FUZZ
@given(
    armed=st.booleans(),
    intended=st.sampled_from(sorted(MODES)),
    updated=st.booleans(),
    failing=st.integers(0, int(max(Requirement)) * 2 - 1),
    gcs=st.booleans(),
    manual=st.booleans(),
    battery=any_int,
    geofence=st.booleans(),
    gf_action=st.integers(0, 5),
    dt=st.integers(-(10**9), 10**9),
)
def test_any_failure_conditions_give_a_mode(armed, intended, updated, failing, gcs, manual, battery, geofence,
                                            gf_action, dt):
    failsafe = Failsafe({"COM_FAIL_ACT_T": 1.0, "NAV_DLL_ACT": 2, "NAV_RCL_ACT": 2, "COM_LOW_BAT_ACT": 3})
    conditions = FailsafeConditions(Requirement(failing), gcs, manual, battery, geofence)
    now = 10**10
    for _ in range(3):
        now += dt
        result = failsafe.update(now, armed, intended, updated, conditions, gf_action)
        assert result.nav_state in MODES


land_inputs = st.builds(
    LandDetectorInputs,
    armed=st.booleans(),
    local_position_timestamp_us=any_int,
    z_valid=st.booleans(),
    v_xy_valid=st.booleans(),
    v_z_valid=st.booleans(),
    vx=nasty_float,
    vy=nasty_float,
    vz=nasty_float,
    z_deriv=nasty_float,
    dist_bottom_valid=st.booleans(),
    dist_bottom=nasty_float,
    angular_velocity=vec3,
    acceleration=vec3,
    throttle=nasty_float,
    climb_rate_control=st.booleans(),
    velocity_setpoint_z=nasty_float,
    hover_thrust=nasty_float,
    hover_thrust_timestamp_us=any_int,
    takeoff_state=st.sampled_from([1, 2, 3, 4, 5]),
)


@FUZZ
@given(steps=st.lists(land_inputs, min_size=1, max_size=3), state=any_int)
def test_the_land_detector_takes_any_input(steps, state):
    detector = MulticopterLandDetector()
    now = 1_000_000
    for inp in steps:
        now += 20_000
        result = detector.update(now, inp)
        assert isinstance(result.landed, bool)
    assert takeoff_state(state) is None or 1 <= state <= 5
