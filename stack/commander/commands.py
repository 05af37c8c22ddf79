"""Builders for the ``vehicle_command`` messages the commander understands, encoded the way QGroundControl
and PX4's ``commander`` CLI send them (see :mod:`stack.commander.state_machine` for the meaning)."""

from __future__ import annotations

import math

from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES, nav_state_from_name
from stack.msg.system import VehicleCommand

NAN = math.nan
CMD = VehicleCommand
TAKEOFF_ALTITUDE_RELATIVE = 1
"""NAV_TAKEOFF param2 value saying param7 is metres above home rather than AMSL (our extension)."""


def arm_command(force: bool = False) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=1.0, param2=CMD.ARM_FORCE_MAGIC if force else 0.0)


def disarm_command(force: bool = False) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=0.0, param2=CMD.ARM_FORCE_MAGIC if force else 0.0)


def set_mode_command(name: str) -> VehicleCommand:
    """MAV_CMD_DO_SET_MODE with PX4's custom main/sub mode for a mode name ("posctl", "auto:loiter", "hold"...).
    Raises ValueError for an unknown name."""
    main, sub = MODES[nav_state_from_name(name)].custom_mode
    return CMD(
        command=CMD.VEHICLE_CMD_DO_SET_MODE,
        param1=float(MAV_MODE_FLAG_CUSTOM_MODE_ENABLED),
        param2=float(main),
        param3=float(sub),
    )


def set_nav_state_command(nav_state: int) -> VehicleCommand:
    """The PX4-internal SET_NAV_STATE command: switch straight to a ``vehicle_status`` nav_state."""
    return CMD(command=CMD.VEHICLE_CMD_SET_NAV_STATE, param1=float(nav_state))


def takeoff_command(altitude: float = NAN, relative: bool = True, yaw_deg: float = NAN) -> VehicleCommand:
    """NAV_TAKEOFF to ``altitude`` metres above home (``relative``) or AMSL; NaN uses MIS_TAKEOFF_ALT."""
    return CMD(
        command=CMD.VEHICLE_CMD_NAV_TAKEOFF,
        param2=float(TAKEOFF_ALTITUDE_RELATIVE) if relative else 0.0,
        param4=yaw_deg,
        param7=altitude,
    )


def land_command() -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_NAV_LAND)


def return_command() -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_NAV_RETURN_TO_LAUNCH)


def hold_command() -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_NAV_LOITER_UNLIM)


def goto_local_command(
    north: float, east: float, down: float, yaw_deg: float = NAN, speed: float = NAN
) -> VehicleCommand:
    """Go to a local NED position [m] (NaN components keep the current value)."""
    return CMD(
        command=CMD.VEHICLE_CMD_DO_REPOSITION_LOCAL,
        param1=speed,
        param2=1.0,
        param4=yaw_deg,
        param5=north,
        param6=east,
        param7=down,
    )


def goto_global_command(
    lat_deg: float, lon_deg: float, alt_amsl: float, yaw_deg: float = NAN, speed: float = NAN
) -> VehicleCommand:
    """MAV_CMD_DO_REPOSITION as QGroundControl sends it (change-mode flag set)."""
    return CMD(
        command=CMD.VEHICLE_CMD_DO_REPOSITION,
        param1=speed,
        param2=1.0,
        param4=yaw_deg,
        param5=lat_deg,
        param6=lon_deg,
        param7=alt_amsl,
    )


def mission_start_command(first_item: int = 0) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_MISSION_START, param1=float(first_item), param2=0.0)
