"""Checks a ``vehicle_command`` passes before anything acts on it, beyond each parameter being finite.

* Addressing, as PX4 ``Commander::handle_command`` (``src/modules/commander/Commander.cpp``): a command is for
  this vehicle when its ``target_system`` is MAV_SYS_ID or 0 (broadcast) and its ``target_component`` is
  MAV_COMP_ID or 0; any other is ignored, without an acknowledgement (it is another vehicle's to answer).
* Arming and disarming (MAV_CMD_COMPONENT_ARM_DISARM, PX4 ``Commander::handle_command``): param1 rounds to 1 (arm)
  or 0 (disarm), anything else is refused; param2 = 21196 forces it (skips the checks). The simulated Pixhawk's
  commander reads the command the same way.
* Takeoff altitude: above home within MIS_TAKEOFF_ALT's range (its minimum excluded, a takeoff must climb).
* Go-to target (DO_REPOSITION): at most MIS_DIST_1WP from home horizontally and vertically (PX4's sanity limit
  for the first waypoint against a mistyped coordinate; a go-to is a one-waypoint flight) and, when it gives an
  altitude, at least NAV_MC_ALT_RAD above home, so that it never flies into the ground.
"""

from __future__ import annotations

import math

from stack.msg.system import VehicleCommand
from stack.params import catalogue

TAKEOFF_ALTITUDE = catalogue.get("MIS_TAKEOFF_ALT")
BROADCAST = 0


def addressed_to(cmd: VehicleCommand, system_id: int, component_id: int) -> bool:
    """Whether ``cmd`` is for this system and component (0 addresses all)."""
    return cmd.target_system in (BROADCAST, system_id) and cmd.target_component in (BROADCAST, component_id)


def arm_action(param1: float) -> int | None:
    """COMPONENT_ARM_DISARM param1 as ARMING_ACTION_ARM (1) or ARMING_ACTION_DISARM (0), None for anything else."""
    action = round(param1) if math.isfinite(param1) else -1
    return action if action in (VehicleCommand.ARMING_ACTION_DISARM, VehicleCommand.ARMING_ACTION_ARM) else None


def arm_forced(param2: float) -> bool:
    """Whether COMPONENT_ARM_DISARM param2 forces the arming or disarming (PX4's magic number 21196)."""
    return math.isfinite(param2) and round(param2) == VehicleCommand.ARM_FORCE_MAGIC


def takeoff_altitude_refusal(altitude: float) -> str:
    """Why a takeoff to ``altitude`` metres above home is refused, or ""."""
    low, high = float(TAKEOFF_ALTITUDE.min or 0.0), float(TAKEOFF_ALTITUDE.max or math.inf)
    if not low < altitude <= high:
        return f"Takeoff: {altitude:.1f} m above home is outside MIS_TAKEOFF_ALT's range ({low:g}, {high:g}] m"
    return ""


def goto_refusal(
    home: tuple[float, float, float],
    target: tuple[float, float, float],
    altitude_given: bool,
    max_distance: float,
    min_height: float,
) -> tuple[str, int]:
    """Why a go-to to ``target`` (local NED, finite) is refused and the offending DO_REPOSITION parameter (5 for
    the horizontal position, 7 for the altitude), or ("", 0).

    ``home`` is home's local NED position, ``max_distance`` MIS_DIST_1WP (≤ 0: no limit), ``min_height``
    NAV_MC_ALT_RAD; the height floor is checked only when the command gave an altitude (NaN keeps the current
    one, which is where the vehicle flies already)."""
    north, east, down = target
    height = home[2] - down
    if altitude_given and height < min_height:
        return (
            f"Reposition denied: target {height:.1f} m above home, below NAV_MC_ALT_RAD {min_height:g} m "
            "(it would fly into the ground)",
            7,
        )
    if max_distance > 0.0:
        distance = math.hypot(north - home[0], east - home[1])
        if distance > max_distance:
            return f"Reposition denied: target {distance:.1f} m from home, beyond MIS_DIST_1WP {max_distance:g} m", 5
        if height > max_distance:
            return f"Reposition denied: target {height:.1f} m above home, beyond MIS_DIST_1WP {max_distance:g} m", 7
    return "", 0
