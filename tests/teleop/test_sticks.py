"""The sticks as manual_control_setpoint, the last setpoint before a stick source stops, and the commands of
actions (as `stack cmd` sends them)."""

import pytest

from stack.commander import commands
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus as NS
from stack.teleop import actions
from stack.teleop.sticks import Sticks, parting, setpoint


def test_the_setpoint_is_valid_and_carries_the_sticks():
    sp = setpoint(Sticks(0.1, -0.2, 0.3, 0.4), 1_000_000)
    assert (sp.roll, sp.pitch, sp.yaw, sp.throttle) == (0.1, -0.2, 0.3, 0.4)
    assert sp.valid and sp.timestamp_sample == 1_000_000
    assert sp.data_source == ManualControlSetpoint.SOURCE_MAVLINK_0


@pytest.mark.parametrize(
    ("nav_state", "throttle"),
    [
        (NS.NAVIGATION_STATE_POSCTL, 0.0),  # a climb rate: centred holds the altitude
        (NS.NAVIGATION_STATE_ALTCTL, 0.0),
        (NS.NAVIGATION_STATE_AUTO_RTL, 0.0),
        (NS.NAVIGATION_STATE_STAB, 0.3),  # thrust: left where the pilot had it
        (NS.NAVIGATION_STATE_ACRO, 0.3),
        (NS.NAVIGATION_STATE_EXTERNAL1, 0.3),
        (None, 0.3),  # the mode unknown
    ],
)
def test_the_parting_sticks_are_centred_and_the_throttle_too_where_it_is_a_climb_rate(nav_state, throttle):
    assert parting(Sticks(0.5, -0.5, 1.0, 0.3), nav_state) == Sticks(0.0, 0.0, 0.0, throttle)


def test_actions_are_stack_cmds_commands_and_labels():
    assert actions.command("arm") == ("arm", commands.arm_command())
    assert actions.command("disarm") == ("disarm", commands.disarm_command())
    assert actions.command("posctl") == ("mode Position", commands.set_mode_command("posctl"))
    assert actions.command("hold") == ("mode Hold", commands.set_mode_command("auto:loiter"))
    assert actions.check("rotors") == "rotors"
    with pytest.raises(ValueError, match="unknown mode 'fly'"):
        actions.check("fly")
