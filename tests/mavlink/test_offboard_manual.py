"""Offboard setpoints and stick input from a link."""

import math

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mavlink import offboard
from stack.mavlink.manual import LOSS_US, ManualInput, Refused, manual_control
from stack.mavlink.offboard import REPUBLISH_US
from stack.msg.setpoints import TrajectorySetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint

NAN = math.nan
IGNORE_ACCEL_YAW_RATE = (
    M.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | M.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
    | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
)
IGNORE_VELOCITY = (
    M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE
)
IGNORE_POSITION = (
    M.POSITION_TARGET_TYPEMASK_X_IGNORE | M.POSITION_TARGET_TYPEMASK_Y_IGNORE | M.POSITION_TARGET_TYPEMASK_Z_IGNORE
)


def _position(mask: int, frame: int = M.MAV_FRAME_LOCAL_NED, xyz=(1.0, 2.0, -3.0), v=(0.5, 0.0, 0.0), yaw=0.3):
    return M.MAVLink_set_position_target_local_ned_message(0, 1, 1, frame, mask, *xyz, *v, 0.0, 0.0, 0.0, yaw, 0.0)


def test_a_position_setpoint_controls_what_its_mask_leaves_and_says_so():
    sp, mode = offboard.position_target(_position(IGNORE_ACCEL_YAW_RATE | IGNORE_VELOCITY), 0.0, 7)
    assert isinstance(sp, TrajectorySetpoint) and sp.position == (1.0, 2.0, -3.0) and sp.yaw == 0.3
    assert all(math.isnan(v) for v in (*sp.velocity, *sp.acceleration, sp.yawspeed))
    assert (mode.position, mode.velocity, mode.acceleration, mode.timestamp) == (True, False, False, 7)


def test_a_body_frame_velocity_turns_with_the_heading():
    sp, mode = offboard.position_target(
        _position(IGNORE_ACCEL_YAW_RATE | IGNORE_POSITION, M.MAV_FRAME_BODY_NED), math.pi / 2, 0
    )
    assert sp.velocity == pytest.approx((0.0, 0.5, 0.0), abs=1e-9) and (mode.position, mode.velocity) == (False, True)


@pytest.mark.parametrize(
    ("msg", "words"),
    [
        (_position(IGNORE_ACCEL_YAW_RATE | IGNORE_VELOCITY, xyz=(NAN, 0.0, 0.0)), "position x is nan"),
        (_position(IGNORE_ACCEL_YAW_RATE, v=(0.0, math.inf, 0.0)), "velocity y is inf"),
        (_position(M.POSITION_TARGET_TYPEMASK_FORCE_SET), "force"),
        (_position(IGNORE_ACCEL_YAW_RATE, frame=M.MAV_FRAME_GLOBAL), "frame 0"),
        (_position(IGNORE_ACCEL_YAW_RATE, frame=M.MAV_FRAME_BODY_NED), "positions in MAV_FRAME_BODY_NED"),
        (_position(IGNORE_ACCEL_YAW_RATE | IGNORE_POSITION | IGNORE_VELOCITY), "no position, velocity"),
    ],
)
def test_a_bad_position_setpoint_is_refused(msg, words):
    with pytest.raises(offboard.Refused, match=words):
        offboard.position_target(msg, 0.0, 0)


def _attitude(mask: int, q=(1.0, 0.0, 0.0, 0.0), rates=(0.1, 0.2, 0.3), thrust=0.6):
    return M.MAVLink_set_attitude_target_message(0, 1, 1, mask, list(q), *rates, thrust)


def test_an_attitude_or_rates_with_a_collective_thrust():
    sp, mode = offboard.attitude_target(_attitude(0b111), 0)
    assert isinstance(sp, VehicleAttitudeSetpoint) and sp.q_d == (1.0, 0.0, 0.0, 0.0)
    assert sp.thrust_body == (0.0, 0.0, -0.6) and mode.attitude and not mode.body_rate
    rates, mode = offboard.attitude_target(_attitude(M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE), 0)
    assert isinstance(rates, VehicleRatesSetpoint) and (rates.roll, rates.pitch, rates.yaw) == pytest.approx(
        (0.1, 0.2, 0.3)
    )
    assert mode.body_rate and not mode.attitude


@pytest.mark.parametrize(
    ("msg", "words"),
    [
        (_attitude(0, q=(0.5, 0.0, 0.0, 0.0)), "not a unit quaternion"),
        (_attitude(0, q=(NAN, 0.0, 0.0, 0.0)), "not a unit quaternion"),
        (_attitude(0, thrust=1.5), "outside 0..1"),
        (_attitude(M.ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE), "thrust must be given"),
        (_attitude(M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE, rates=(NAN, 0.0, 0.0)), "body rate x is nan"),
        (_attitude(M.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE, rates=(50.0, 0.0, 0.0)), "beyond"),
    ],
)
def test_a_bad_attitude_setpoint_is_refused(msg, words):
    with pytest.raises(offboard.Refused, match=words):
        offboard.attitude_target(msg, 0)


def test_the_relay_keeps_the_proof_of_life_going_while_the_client_streams():
    relay = offboard.OffboardRelay()
    sp, mode = offboard.position_target(_position(IGNORE_ACCEL_YAW_RATE | IGNORE_VELOCITY), 0.0, 0)
    relay.on_setpoint(sp, mode, 1_000_000)
    first = relay.due(1_000_000, 5_000, in_offboard=False)
    assert [topic.name for topic, _ in first] == ["offboard_control_mode"] and first[0][1].timestamp == 5_000
    assert relay.due(1_010_000, 6_000, in_offboard=True) == []
    out = relay.due(1_020_000, 7_000, in_offboard=True)
    assert [topic.name for topic, _ in out] == ["offboard_control_mode", "trajectory_setpoint"]
    assert out[1][1].timestamp == 7_000
    assert relay.due(1_000_000 + offboard.PROOF_OF_LIFE_US + 1, 8_000, in_offboard=True) == []


def test_sticks_are_scaled_as_px4_does():
    sticks = manual_control(M.MAVLink_manual_control_message(1, 500, -1000, 750, 250, 3), 42)
    assert (sticks.pitch, sticks.roll, sticks.throttle, sticks.yaw) == (0.5, -1.0, 0.5, 0.25)
    assert sticks.valid and sticks.buttons == 3 and sticks.timestamp == 42


@pytest.mark.parametrize(("x", "z"), [(1001, 500), (0, -1), (0, 1001), (32767, 500)])
def test_sticks_out_of_range_are_refused(x, z):
    with pytest.raises(Refused):
        manual_control(M.MAVLink_manual_control_message(1, x, 0, z, 0, 0), 0)


def test_sticks_are_repeated_while_they_come_and_published_once_more_as_invalid_when_they_stop():
    manual = ManualInput()
    t0 = 1_000_000
    manual.on_sticks(manual_control(M.MAVLink_manual_control_message(1, 0, 0, 500, 0, 0), 1), t0)
    assert manual.due(t0 + REPUBLISH_US - 1, 2) is None
    again = manual.due(t0 + REPUBLISH_US, 3)
    assert again is not None and again.valid and again.timestamp == 3
    assert manual.due(t0 + REPUBLISH_US + 1, 4) is None
    assert manual.due(t0 + LOSS_US, 5) is not None
    lost = manual.due(t0 + LOSS_US + 1, 6)
    assert lost is not None and not lost.valid and lost.throttle == 0.0 and lost.timestamp == 6
    assert manual.due(9_000_000, 7) is None

