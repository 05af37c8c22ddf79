"""What a key or a gamepad button asks of the vehicle: arm, disarm or a mode, sent as ``stack cmd`` sends it."""

from __future__ import annotations

from stack.commander import commands
from stack.commander.modes import MODES, nav_state_from_name
from stack.msg.system import VehicleCommand

ARM = "arm"
DISARM = "disarm"


def check(action: str) -> str:
    """``action`` if it is one: arm, disarm or a mode name (``stack cmd mode``'s); ValueError otherwise."""
    if action not in (ARM, DISARM):
        nav_state_from_name(action)
    return action


def command(action: str) -> tuple[str, VehicleCommand]:
    """The label ``stack cmd`` prints for the action, and its ``vehicle_command``."""
    if action == ARM:
        return "arm", commands.arm_command()
    if action == DISARM:
        return "disarm", commands.disarm_command()
    return f"mode {MODES[nav_state_from_name(action)].name}", commands.set_mode_command(action)
