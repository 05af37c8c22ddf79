"""DO_SET_MISSION_CURRENT: the item a mission flies next, as a ground station sets it (MISSION_SET_CURRENT)."""

import math

import pytest

from stack.commander import commands as C
from stack.commander.state_machine import SUPPORTED_COMMANDS
from stack.msg.system import VehicleCommand
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import make_clock

CMD = VehicleCommand


def _set_current(seq: float, reset: float = math.nan) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_DO_SET_MISSION_CURRENT, param1=seq, param2=reset)


def test_the_next_item_is_handed_to_the_navigator_without_a_mode_change():
    clock = make_clock()
    clock.overrides = {"mission_count": 4}
    clock.step()
    assert clock.send(_set_current(2.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert (out.navigation.mission_start_index, out.navigation.mission_start_counter) == (2, 1)
    assert out.vehicle_status.nav_state != NS.NAVIGATION_STATE_AUTO_MISSION and not clock.commander.armed
    assert clock.send(_set_current(-1.0, reset=1.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().navigation.mission_start_index == 0
    assert clock.send(_set_current(-1.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().navigation.mission_start_counter == 2  # −1 without reset: nothing to change


@pytest.mark.parametrize("seq", [4.0, -2.0, 1.5, math.inf])
def test_an_item_outside_the_mission_is_denied(seq):
    clock = make_clock()
    clock.overrides = {"mission_count": 4}
    clock.step()
    ack = clock.send(_set_current(seq))
    assert (ack.result, ack.result_param2) == (ACK.VEHICLE_CMD_RESULT_DENIED, 1)
    assert "must be −1…3" in ack.reason
    assert clock.step().navigation.mission_start_counter == 0


def test_without_a_mission_it_is_denied():
    clock = make_clock()
    ack = clock.send(_set_current(0.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_DENIED and "no valid mission" in ack.reason


def test_in_mission_mode_the_vehicle_goes_there_at_once():
    clock = make_clock()
    clock.overrides = {"mission_count": 5}
    clock.step()
    clock.send(C.mission_start_command(0))
    assert clock.send(_set_current(3.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert (out.navigation.mission_start_index, out.navigation.mission_start_counter) == (3, 2)


def test_the_supported_commands_are_the_handled_ones():
    supported = SUPPORTED_COMMANDS
    assert CMD.VEHICLE_CMD_DO_SET_MISSION_CURRENT in supported
    assert CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM in supported
    assert CMD.VEHICLE_CMD_DO_FLIGHTTERMINATION not in supported
