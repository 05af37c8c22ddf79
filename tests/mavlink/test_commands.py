"""COMMAND_LONG, COMMAND_INT and SET_MODE → vehicle_command; COMMAND_ACK back to the sender."""

import math

import pytest
from pymavlink.dialects.v20 import common as M

from stack.commander.state_machine import SUPPORTED_COMMANDS
from stack.mavlink.commands import (
    INT32_MAX,
    PendingCommands,
    Refusal,
    addressed_to,
    from_command_int,
    from_command_long,
    from_set_mode,
)
from stack.msg.system import VehicleCommand as CMD
from stack.msg.system import VehicleCommandAck as ACK

OWN = (1, 1)
GCS = (245, 190)
SUPPORTED = SUPPORTED_COMMANDS
NAN = math.nan


def _long(command: int, *params: float) -> M.MAVLink_command_long_message:
    p = list(params) + [NAN] * (7 - len(params))
    return M.MAVLink_command_long_message(1, 1, command, 0, *p)


def _int(command: int, frame: int, x: int, y: int, z: float, *params: float) -> M.MAVLink_command_int_message:
    p = list(params) + [NAN] * (4 - len(params))
    return M.MAVLink_command_int_message(1, 1, frame, command, 0, 0, *p, x, y, z)


def test_a_command_keeps_its_sender_and_its_nan_parameters():
    cmd = from_command_long(_long(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0), GCS, OWN, SUPPORTED)
    assert (cmd.command, cmd.param1) == (CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, 1.0)
    assert all(math.isnan(p) for p in (cmd.param2, cmd.param3, cmd.param7))
    assert (cmd.source_system, cmd.source_component, cmd.target_system, cmd.from_external) == (245, 190, 1, True)


@pytest.mark.parametrize(
    "command", [M.MAV_CMD_DO_SET_HOME, M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_DO_FLIGHTTERMINATION, 31010]
)
def test_what_the_stack_does_not_do_is_unsupported_at_once(command):
    assert from_command_long(_long(command, 1.0), GCS, OWN, SUPPORTED) == Refusal(M.MAV_RESULT_UNSUPPORTED)


def test_qgroundcontrols_takeoff_is_an_amsl_altitude_and_param2_stays_unused():
    cmd = from_command_long(_long(M.MAV_CMD_NAV_TAKEOFF, -1.0, 1.0, 0.0, NAN, NAN, NAN, 495.0), GCS, OWN, SUPPORTED)
    assert (cmd.param1, cmd.param7) == (-1.0, 495.0) and math.isnan(cmd.param2)


def test_reposition_yaw_arrives_in_radians_as_px4_reads_it():
    cmd = from_command_long(_long(M.MAV_CMD_DO_REPOSITION, -1.0, 1.0, 0.0, math.pi / 2), GCS, OWN, SUPPORTED)
    assert cmd.param4 == pytest.approx(90.0)
    nan_yaw = from_command_long(_long(M.MAV_CMD_DO_REPOSITION, -1.0, 1.0, 0.0, NAN), GCS, OWN, SUPPORTED)
    assert math.isnan(nan_yaw.param4)


def test_command_int_positions_in_dege7_and_its_frames():
    amsl = from_command_int(_int(M.MAV_CMD_DO_REPOSITION, 0, 473977420, 85455940, 500.0), GCS, OWN, SUPPORTED, NAN)
    assert (amsl.param5, amsl.param6, amsl.param7) == pytest.approx((47.397742, 8.545594, 500.0))
    rel = from_command_int(_int(M.MAV_CMD_DO_REPOSITION, 6, 473977420, 85455940, 10.0), GCS, OWN, SUPPORTED, 488.0)
    assert rel.param7 == 498.0
    keep = from_command_int(_int(M.MAV_CMD_DO_REPOSITION, 5, INT32_MAX, INT32_MAX, NAN), GCS, OWN, SUPPORTED, NAN)
    assert math.isnan(keep.param5) and math.isnan(keep.param6) and math.isnan(keep.param7)


def test_command_int_refuses_what_it_cannot_place():
    no_home = from_command_int(_int(M.MAV_CMD_DO_REPOSITION, 3, 0, 0, 10.0), GCS, OWN, SUPPORTED, NAN)
    assert isinstance(no_home, Refusal) and (no_home.result, no_home.param) == (M.MAV_RESULT_DENIED, 7)
    local = from_command_int(_int(M.MAV_CMD_DO_REPOSITION, M.MAV_FRAME_LOCAL_NED, 0, 0, 1.0), GCS, OWN, SUPPORTED, 0.0)
    assert isinstance(local, Refusal) and "frame 1" in local.reason
    arm = from_command_int(_int(M.MAV_CMD_COMPONENT_ARM_DISARM, 1, 0, 0, 0.0, 1.0), GCS, OWN, SUPPORTED, NAN)
    assert arm.param1 == 1.0  # the frame only matters for commands that take a position


def test_set_mode_becomes_do_set_mode_with_px4s_main_and_sub_mode():
    cmd = from_set_mode(M.MAVLink_set_mode_message(1, 1, 4 << 16 | 5 << 24), GCS, OWN)
    assert (cmd.command, cmd.param1, cmd.param2, cmd.param3) == (CMD.VEHICLE_CMD_DO_SET_MODE, 1.0, 4.0, 5.0)


def test_addressing():
    assert addressed_to(1, 1, OWN) and addressed_to(0, 0, OWN) and addressed_to(1, 0, OWN)
    assert not addressed_to(2, 1, OWN) and not addressed_to(1, 190, OWN)


def test_the_ack_goes_to_the_sender_of_a_forwarded_command_only():
    pending = PendingCommands(timeout_us=3_000_000)
    cmd = from_command_long(_long(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0), GCS, OWN, SUPPORTED)
    assert pending.add(cmd, 0) and not pending.add(cmd, 100_000)  # a resend while pending is not forwarded
    other = ACK(command=cmd.command, result=0, target_system=255, target_component=190)  # `stack cmd`'s
    assert pending.answer(other) is None
    ack = pending.answer(ACK(command=cmd.command, result=1, result_param2=0, target_system=245, target_component=190))
    assert (ack.command, ack.result, ack.target_system, ack.target_component) == (400, 1, 245, 190)
    assert len(pending) == 0 and pending.add(cmd, 200_000)


def test_an_unanswered_command_fails_after_the_timeout():
    pending = PendingCommands(timeout_us=3_000_000)
    pending.add(from_command_long(_long(M.MAV_CMD_NAV_LAND), GCS, OWN, SUPPORTED), 0)
    assert pending.expired(3_000_000) == []
    (ack,) = pending.expired(3_000_001)
    assert (ack.command, ack.result, ack.target_system) == (M.MAV_CMD_NAV_LAND, M.MAV_RESULT_FAILED, 245)
    assert len(pending) == 0


def test_the_same_command_with_other_parameters_is_forwarded_and_answered_in_turn():
    pending = PendingCommands(timeout_us=3_000_000)
    arm = from_command_long(_long(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0), GCS, OWN, SUPPORTED)
    disarm = from_command_long(_long(M.MAV_CMD_COMPONENT_ARM_DISARM, 0.0), GCS, OWN, SUPPORTED)
    assert pending.add(arm, 0) and pending.add(disarm, 1000) and not pending.add(disarm, 2000)
    assert len(pending) == 2
    for result in (0, 1):
        ack = pending.answer(ACK(command=400, result=result, target_system=245, target_component=190))
        assert ack is not None and ack.result == result
    assert pending.answer(ACK(command=400, result=0, target_system=245, target_component=190)) is None
