"""Who the vehicle says it is: HEARTBEAT and AUTOPILOT_VERSION as PX4 sends them.

HEARTBEAT follows PX4's ``get_mavlink_mode_state`` (``src/modules/mavlink/mavlink_messages.cpp``): MAV_AUTOPILOT_PX4,
base_mode with CUSTOM_MODE_ENABLED, SAFETY_ARMED when armed and the manual/stabilize/guided/auto flags of the
mode, custom_mode in PX4's main/sub encoding (:mod:`stack.mavlink.px4_modes`), system_status STANDBY or ACTIVE.
AUTOPILOT_VERSION carries the capabilities of what this module implements (MISSION_INT, COMMAND_INT, MAVLink 2,
bytewise parameters, SET_ATTITUDE_TARGET, SET_POSITION_TARGET_LOCAL_NED; no FTP, fence or rally) and the stack's
own version (not PX4's).
"""

from __future__ import annotations

import hashlib
import importlib.metadata

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.msg.system import VehicleStatus as NS
from stack.record.provenance import git_commit

CAPABILITIES = (
    mavlink2.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    | mavlink2.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET
    | mavlink2.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
    | mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)

_AUTO = (
    mavlink2.MAV_MODE_FLAG_AUTO_ENABLED
    | mavlink2.MAV_MODE_FLAG_STABILIZE_ENABLED
    | mavlink2.MAV_MODE_FLAG_GUIDED_ENABLED
)
_MANUAL = mavlink2.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
_STABILIZE = mavlink2.MAV_MODE_FLAG_STABILIZE_ENABLED
MODE_FLAGS: dict[int, int] = {
    NS.NAVIGATION_STATE_MANUAL: _MANUAL | _STABILIZE,  # a rotary wing's Manual is stabilized
    NS.NAVIGATION_STATE_ACRO: _MANUAL,
    NS.NAVIGATION_STATE_RATTITUDE: _MANUAL,
    NS.NAVIGATION_STATE_STAB: _MANUAL | _STABILIZE,
    NS.NAVIGATION_STATE_ALTCTL: _MANUAL | _STABILIZE,
    NS.NAVIGATION_STATE_POSCTL: _MANUAL | _STABILIZE | mavlink2.MAV_MODE_FLAG_GUIDED_ENABLED,
    NS.NAVIGATION_STATE_AUTO_TAKEOFF: _AUTO,
    NS.NAVIGATION_STATE_AUTO_MISSION: _AUTO,
    NS.NAVIGATION_STATE_AUTO_LOITER: _AUTO,
    NS.NAVIGATION_STATE_AUTO_RTL: _AUTO,
    NS.NAVIGATION_STATE_AUTO_LAND: _AUTO,
    NS.NAVIGATION_STATE_DESCEND: _AUTO,
    NS.NAVIGATION_STATE_OFFBOARD: _AUTO,
    NS.NAVIGATION_STATE_TERMINATION: _MANUAL,
}
"""The base_mode flags of each mode (PX4 ``get_mavlink_navigation_mode``)."""


def heartbeat(status: NS | None, mav_type: int) -> dict[str, int]:
    """The HEARTBEAT fields for ``vehicle_status`` (None before the commander has published: UNINIT)."""
    if status is None:
        return {
            "type": mav_type,
            "autopilot": mavlink2.MAV_AUTOPILOT_PX4,
            "base_mode": mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            "custom_mode": 0,
            "system_status": mavlink2.MAV_STATE_UNINIT,
        }
    armed = status.arming_state == NS.ARMING_STATE_ARMED
    base = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | MODE_FLAGS.get(status.nav_state, 0)
    if armed:
        base |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    mode = px4_modes.from_nav_state(status.nav_state)
    if status.nav_state == NS.NAVIGATION_STATE_TERMINATION:
        system_status = mavlink2.MAV_STATE_FLIGHT_TERMINATION
    else:
        system_status = mavlink2.MAV_STATE_ACTIVE if armed else mavlink2.MAV_STATE_STANDBY
    return {
        "type": mav_type,
        "autopilot": mavlink2.MAV_AUTOPILOT_PX4,
        "base_mode": base,
        "custom_mode": px4_modes.encode(mode) if mode is not None else 0,
        "system_status": system_status,
    }


def software_version(version: str) -> int:
    """AUTOPILOT_VERSION.flight_sw_version: major, minor, patch in bytes 3..1, FIRMWARE_VERSION_TYPE in byte 0."""
    parts = [int(p) if p.isdigit() else 0 for p in version.split(".")[:3]]
    major, minor, patch = [*parts, 0, 0, 0][:3]
    return (major & 0xFF) << 24 | (minor & 0xFF) << 16 | (patch & 0xFF) << 8 | mavlink2.FIRMWARE_VERSION_TYPE_DEV


def autopilot_version(vehicle: str, system_id: int) -> mavlink2.MAVLink_autopilot_version_message:
    """AUTOPILOT_VERSION: capabilities, the stack's version, the first 8 bytes of its git commit, a uid that
    stays the same for the vehicle and system id."""
    commit = git_commit()
    # PX4 (mavlink_messages.cpp) copies px4_firmware_version_binary(), the first 16 hex digits of its git hash as
    # a 64-bit integer, into flight_custom_version on a little-endian machine: the bytes come last digit first.
    custom = list(bytes.fromhex(commit[:16])[::-1]) if commit else [0] * 8
    uid = int.from_bytes(hashlib.sha256(f"{vehicle}/{system_id}".encode()).digest()[:8], "little")
    try:
        version = importlib.metadata.version("stack")
    except importlib.metadata.PackageNotFoundError:
        version = "0.0.0"
    return mavlink2.MAVLink_autopilot_version_message(
        capabilities=CAPABILITIES,
        flight_sw_version=software_version(version),
        middleware_sw_version=0,
        os_sw_version=0,
        board_version=0,
        flight_custom_version=custom,
        middleware_custom_version=[0] * 8,
        os_custom_version=[0] * 8,
        vendor_id=0,
        product_id=0,
        uid=uid,
        uid2=[0] * 18,
    )
