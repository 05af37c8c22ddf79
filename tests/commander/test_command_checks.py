"""The checks a command passes before the commander acts: its address, the takeoff altitude's range, the go-to
target's distance from home and height, and manual control input for the manual modes."""

import math

import pytest

from stack.commander import commands as C
from stack.commander.command_checks import addressed_to, goto_refusal, takeoff_altitude_refusal
from stack.commander.land_detector import takeoff_state
from stack.commander.state_machine import Commander
from stack.msg.setpoints import TakeoffState
from stack.msg.system import VehicleCommand
from stack.msg.system import VehicleCommandAck as ACK
from tests.commander.helpers import Clock, make_clock

CMD = VehicleCommand
MANUAL_MODES = ("manual", "stabilized", "acro", "rattitude", "altctl", "posctl")


def _state(clock):
    out = clock.step()
    s = out.vehicle_status
    return (s.arming_state, s.nav_state, s.nav_state_user_intention, out.navigation)


def _flying(**params):
    clock = make_clock(**params)
    assert clock.send(C.takeoff_command(5.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.fly_to((0.0, 0.0, -5.0))
    clock.step(0.1)
    return clock


def _to(cmd: VehicleCommand, system: int, component: int = 1) -> VehicleCommand:
    return CMD(**{**{f: getattr(cmd, f) for f in cmd.__struct_fields__}, "target_system": system,
                  "target_component": component})


def test_a_command_for_another_system_or_component_is_ignored_unanswered_and_changes_nothing():
    clock = make_clock()
    before = _state(clock)
    assert clock.send(_to(C.arm_command(), 99)) is None
    assert clock.send(_to(C.arm_command(), 1, 191)) is None
    assert _state(clock) == before
    assert not clock.commander.armed
    assert clock.commander.ignored_commands == 2


def test_a_broadcast_or_a_command_for_this_system_is_handled():
    clock = make_clock()
    assert clock.send(_to(C.set_mode_command("hold"), 0, 0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.send(_to(C.arm_command(), 1, 1)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.commander.ignored_commands == 0


def test_the_system_id_is_mav_sys_id():
    clock = make_clock(MAV_SYS_ID=7, MAV_COMP_ID=2)
    assert clock.send(_to(C.arm_command(), 1)) is None
    assert clock.send(_to(C.arm_command(), 7, 1)) is None
    assert clock.send(_to(C.arm_command(), 7, 2)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    status = clock.step().vehicle_status
    assert (status.system_id, status.component_id) == (7, 2)
    assert addressed_to(_to(C.arm_command(), 7, 0), 7, 2)


@pytest.mark.parametrize("name", MANUAL_MODES)
def test_in_flight_a_manual_mode_needs_manual_control_input(name):
    clock = _flying()
    before = _state(clock)
    ack = clock.send(C.set_mode_command(name))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason.endswith("is currently not possible: no manual control input")
    assert _state(clock) == before
    clock.sticks = True
    clock.step()
    assert clock.send(C.set_mode_command(name)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_invalid_or_stale_sticks_are_no_manual_control_input():
    clock = _flying(NAV_RCL_ACT=0)
    clock.sticks = True
    clock.overrides = {"manual_control_valid": False}
    clock.step()
    assert "no manual control input" in clock.send(C.set_mode_command("acro")).reason
    clock.sticks = False
    clock.overrides = {"last_manual_control_us": clock.t, "manual_control_valid": True}
    clock.step(0.6)  # older than COM_RC_LOSS_T 0.5 s
    assert "no manual control input" in clock.send(C.set_mode_command("acro")).reason
    assert clock.send(C.set_mode_command("hold")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_disarmed_any_mode_may_be_chosen_as_in_px4():
    clock = make_clock()
    for name in MANUAL_MODES:
        assert clock.send(C.set_mode_command(name)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_takeoff_altitude_within_mis_takeoff_alts_range():
    assert takeoff_altitude_refusal(80.0) == ""
    assert takeoff_altitude_refusal(0.1) == ""
    for bad in (0.0, -1.0, 80.5, 1e9, math.nan):
        assert "outside MIS_TAKEOFF_ALT's range (0, 80] m" in takeoff_altitude_refusal(bad)
    clock = make_clock()
    assert clock.send(C.takeoff_command(80.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().navigation.takeoff_altitude == 80.0


def test_go_to_limits_about_home():
    home = (10.0, -5.0, -1.0)
    assert goto_refusal(home, (10.0 + 900.0, -5.0, -21.0), True, 900.0, 0.8) == ("", 0)
    reason, param = goto_refusal(home, (10.0 + 901.0, -5.0, -21.0), True, 900.0, 0.8)
    assert (reason, param) == ("Reposition denied: target 901.0 m from home, beyond MIS_DIST_1WP 900 m", 5)
    reason, param = goto_refusal(home, (0.0, 0.0, -1000.0), True, 900.0, 0.8)
    assert (reason, param) == ("Reposition denied: target 999.0 m above home, beyond MIS_DIST_1WP 900 m", 7)
    assert goto_refusal(home, (0.0, 0.0, -1.5), True, 900.0, 0.8)[1] == 7
    assert goto_refusal(home, (0.0, 0.0, -1.5), False, 900.0, 0.8) == ("", 0)  # the altitude it flies at now
    assert goto_refusal(home, (1e6, 0.0, -1e6), True, 0.0, 0.8) == ("", 0)  # MIS_DIST_1WP 0: no limit


def test_a_go_to_keeping_the_altitude_is_accepted_low_over_home():
    clock = _flying()
    clock.fly_to((0.0, 0.0, -0.5))
    ack = clock.send(C.goto_local_command(3.0, 0.0, math.nan))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().navigation.reposition[:3] == (3.0, 0.0, -0.5)


def test_a_go_to_needs_a_home():
    clock = Clock(Commander(), overrides={"local_position": None})  # no position on the ground: no home
    assert clock.send(C.arm_command(force=True)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.overrides = {}
    assert clock.fly_to((0.0, 0.0, -5.0)).home is None
    ack = clock.send(C.goto_local_command(1.0, 0.0, -5.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Reposition denied: no home position"


@pytest.mark.parametrize("value", [-1, 0, 6, 255, 2**31])
def test_a_takeoff_status_naming_no_state_is_dropped(value):
    assert takeoff_state(value) is None


def test_a_takeoff_status_state_is_read():
    assert takeoff_state(5) is TakeoffState.FLIGHT
