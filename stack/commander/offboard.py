"""Offboard control: the offboard controller's proof of life, and the control loops its setpoints select.

The offboard signal is present while ``offboard_control_mode`` keeps arriving, each within COM_OF_LOSS_T of
the last (PX4 ``src/modules/commander/HealthAndArmingChecks/checks/offboardCheck.cpp``). Without it a switch to
Offboard is refused; in Offboard the ``vehicle_control_mode`` flags follow the setpoint types the controller
says it streams (PX4 ``src/modules/commander/ModeUtil/control_mode.cpp``, ``vehicle_control_mode_s`` for
``NAVIGATION_STATE_OFFBOARD``).
"""

from __future__ import annotations

import math
from enum import IntEnum

from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, nav_state_from_custom_mode
from stack.msg.system import OffboardControlMode, VehicleCommand, VehicleCommandAck, VehicleStatus
from stack.params import catalogue

PARAMS = catalogue.params("COM_OF_LOSS_T")
"""The Offboard signal's timeout, read by the commander and the simulated Pixhawk."""


class OffboardLossAction(IntEnum):
    """COM_OBL_RC_ACT (PX4 ``failsafe.h`` ``offboard_loss_failsafe_mode``), which the simulated autopilots fly: the
    simulated Pixhawk's and the simulator's takeover (Return mode, 3, is not simulated: the parameter refuses it)."""

    POSITION = 0
    ALTITUDE = 1
    STABILIZED = 2
    RETURN = 3
    LAND = 4
    HOLD = 5
    TERMINATE = 6
    DISARM = 7

NO_SIGNAL_REASON = "Switching to Offboard denied: no offboard signal (offboard_control_mode)"


def signal_alive(last_us: int | None, now_us: int, loss_timeout_s: float) -> bool:
    """Whether the offboard signal's last proof of life (at ``last_us``; None: none yet) is at most COM_OF_LOSS_T
    old at ``now_us``: the rule of the stack's commander and of the simulated Pixhawk's."""
    return last_us is not None and now_us - last_us <= loss_timeout_s * 1e6


def signal_present(ocm: OffboardControlMode | None, now_us: int, loss_timeout_s: float) -> bool:
    """Whether the last ``offboard_control_mode`` (None: none yet) is at most COM_OF_LOSS_T old at ``now_us``."""
    return signal_alive(ocm.timestamp if ocm is not None else None, now_us, loss_timeout_s)


def control_flags(ocm: OffboardControlMode) -> dict[str, bool]:
    """PX4's ``vehicle_control_mode`` flags in Offboard, from what the offboard controller streams: a position,
    velocity or acceleration setpoint runs the position controller from that level down, those and an attitude
    setpoint the attitude loop; anything but torque/thrust or actuator setpoints the rate loop; direct actuator
    setpoints bypass the allocator."""
    flags = {"flag_control_offboard_enabled": True, "flag_control_allocation_enabled": True}
    if ocm.position or ocm.velocity or ocm.acceleration:
        flags |= {
            "flag_multicopter_position_control_enabled": True,
            "flag_control_position_enabled": ocm.position,
            "flag_control_velocity_enabled": ocm.position or ocm.velocity,
            "flag_control_altitude_enabled": ocm.position,
            "flag_control_climb_rate_enabled": ocm.position or ocm.velocity,
            "flag_control_acceleration_enabled": True,
        }
    if ocm.position or ocm.velocity or ocm.acceleration or ocm.attitude:
        flags["flag_control_attitude_enabled"] = True
    if not ocm.thrust_and_torque and not ocm.direct_actuator:
        flags["flag_control_rates_enabled"] = True
    if ocm.direct_actuator:
        flags["flag_control_allocation_enabled"] = False
    return flags


def control_flags_now(ocm: OffboardControlMode | None, now_us: int, loss_timeout_s: float) -> dict[str, bool] | None:
    """The control flags of Offboard now, or None while the offboard signal is missing."""
    return control_flags(ocm) if ocm is not None and signal_present(ocm, now_us, loss_timeout_s) else None


def requests_offboard(cmd: VehicleCommand) -> bool:
    """Whether the command asks for Offboard: SET_NAV_STATE to it, or DO_SET_MODE with PX4's Offboard custom mode."""
    if cmd.command == VehicleCommand.VEHICLE_CMD_SET_NAV_STATE:
        return cmd.param1 == VehicleStatus.NAVIGATION_STATE_OFFBOARD
    if cmd.command != VehicleCommand.VEHICLE_CMD_DO_SET_MODE or not math.isfinite(cmd.param1):
        return False
    if int(cmd.param1) & MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and math.isfinite(cmd.param2):
        sub = int(cmd.param3) if math.isfinite(cmd.param3) else 0
        return nav_state_from_custom_mode(int(cmd.param2), sub) == VehicleStatus.NAVIGATION_STATE_OFFBOARD
    return False


def refusal(
    cmd: VehicleCommand, ocm: OffboardControlMode | None, now_us: int, loss_timeout_s: float
) -> VehicleCommandAck | None:
    """The answer to a command that asks for Offboard while the offboard signal is missing (TEMPORARILY_REJECTED,
    as PX4 answers a mode switch it cannot make now), or None: the commander may handle the command."""
    if not requests_offboard(cmd) or signal_present(ocm, now_us, loss_timeout_s):
        return None
    return VehicleCommandAck(
        command=cmd.command,
        result=VehicleCommandAck.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED,
        target_system=cmd.source_system,
        target_component=cmd.source_component,
        reason=NO_SIGNAL_REASON,
    )
