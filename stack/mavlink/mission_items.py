"""MISSION_ITEM_INT ↔ the stack's mission items (:mod:`stack.mission.items`), I/O-free.

Upload: each MISSION_ITEM_INT becomes a :class:`~stack.mission.items.MissionItem` through the same conversion the
mission files use (``item_from_mavlink``), with ``x``/``y`` scaled as MISSION_ITEM_INT defines them (``common.xml``):
degE7 in global frames, metres × 1e4 in local frames, param5/param6 as they are in MAV_FRAME_MISSION. A command
the stack does not fly is refused MAV_MISSION_UNSUPPORTED, a frame it cannot place MAV_MISSION_UNSUPPORTED_FRAME,
anything else wrong (a latitude beyond ±90°, a negative hold time...) MAV_MISSION_INVALID, with the reason.

Download: each entry of the ``mission`` message goes back out as it was given where it has a geodetic position
(frame, latitude, longitude and altitude as uploaded); an item given in local metres is placed about the
mission's home in GLOBAL_RELATIVE_ALT. Parameters the stack does not keep come back as 0.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink2

from stack.mathlib.geo import MapProjection
from stack.mission import items as mi
from stack.mission.items import GeoPoint, Mission, MissionItem
from stack.mission.transfer import mission_from_message
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import Mission as MissionMsg
from stack.msg.navigation import MissionItemEntry, MissionResult
from stack.msg.system import HomePosition

INT32_MAX = 0x7FFF_FFFF
LOCAL_FRAMES = frozenset({mi.MAV_FRAME_LOCAL_NED})
GLOBAL_FRAMES = mi.GLOBAL_AMSL_FRAMES | mi.GLOBAL_RELATIVE_FRAMES
SPEED_TYPE_GROUND = 1.0
"""DO_CHANGE_SPEED param1: the speed is a ground speed (the only kind a multicopter has)."""
NO_CHANGE = -1.0
"""DO_CHANGE_SPEED param2/param3 value meaning "leave unchanged"."""


class ItemRefused(ValueError):
    """An uploaded item the stack cannot take: ``mission_result`` is the MAV_MISSION_RESULT to answer."""

    def __init__(self, mission_result: int, reason: str) -> None:
        super().__init__(reason)
        self.mission_result = mission_result


def _position_params(frame: int, x: int, y: int) -> tuple[float, float]:
    if frame in LOCAL_FRAMES:
        return x / 1e4, y / 1e4
    if frame == mi.MAV_FRAME_MISSION:
        return float(x), float(y)
    return x / 1e7, y / 1e7


def item_from_mission_item_int(msg: mavlink2.MAVLink_mission_item_int_message, home: GeoPoint | None) -> MissionItem:
    """Raises :class:`ItemRefused`."""
    where = f"Mission item {msg.seq}"
    if msg.command not in mi.COMMAND_NAMES:
        supported = ", ".join(f"{c} ({n})" for c, n in mi.COMMAND_NAMES.items())
        raise ItemRefused(
            mavlink2.MAV_MISSION_UNSUPPORTED, f"{where}: command {msg.command} is not supported ({supported})"
        )
    if msg.command in mi.POSITION_COMMANDS and msg.frame not in (GLOBAL_FRAMES | LOCAL_FRAMES):
        raise ItemRefused(mavlink2.MAV_MISSION_UNSUPPORTED_FRAME, f"{where}: frame {msg.frame} is not supported")
    x, y = _position_params(msg.frame, msg.x, msg.y)
    params = [msg.param1, msg.param2, msg.param3, msg.param4, x, y, msg.z]
    try:
        return mi.item_from_mavlink(msg.seq, msg.command, msg.frame, params, bool(msg.autocontinue), home)
    except ValueError as e:
        raise ItemRefused(mavlink2.MAV_MISSION_INVALID, f"{where}: {e}") from None


def _degrees_or_nan(angle_rad: float) -> float:
    return math.degrees(angle_rad) if math.isfinite(angle_rad) else math.nan


def _params(e: MissionItemEntry) -> tuple[float, float, float, float]:
    if e.command == mi.MAV_CMD_NAV_WAYPOINT:
        return e.hold_time, e.acceptance_radius, 0.0, _degrees_or_nan(e.yaw)
    radius = e.loiter_radius if math.isfinite(e.loiter_radius) else 0.0
    if e.command == mi.MAV_CMD_NAV_LOITER_TIME:
        return e.hold_time, 0.0, radius, math.nan
    if e.command == mi.MAV_CMD_NAV_LOITER_TURNS:
        return e.loiter_turns, 0.0, radius, math.nan
    if e.command == mi.MAV_CMD_NAV_LOITER_UNLIM:
        return 0.0, 0.0, radius, _degrees_or_nan(e.yaw)
    if e.command in (mi.MAV_CMD_NAV_TAKEOFF, mi.MAV_CMD_NAV_LAND):
        return 0.0, 0.0, 0.0, _degrees_or_nan(e.yaw)
    if e.command == mi.MAV_CMD_DO_CHANGE_SPEED:
        return SPEED_TYPE_GROUND, e.speed if math.isfinite(e.speed) else NO_CHANGE, NO_CHANGE, 0.0
    return 0.0, 0.0, 0.0, 0.0


def _e7(degrees: float) -> int:
    return max(-INT32_MAX, min(INT32_MAX, round(degrees * 1e7)))


def mission_item_int(
    e: MissionItemEntry, seq: int, home: GeoPoint | None, target: tuple[int, int], current: bool = False
) -> mavlink2.MAVLink_mission_item_int_message:
    """The MISSION_ITEM_INT for a downloaded item (``home``: the mission's, for items given in local metres)."""
    p1, p2, p3, p4 = _params(e)
    frame, x, y, z = e.frame, 0, 0, math.nan
    if e.command in mi.POSITION_COMMANDS:
        if e.frame in GLOBAL_FRAMES and math.isfinite(e.lat) and math.isfinite(e.lon):
            x, y = _e7(e.lat), _e7(e.lon)
            z = e.alt
        elif e.frame in GLOBAL_FRAMES:  # a takeoff or landing "here"
            z = e.alt
        elif home is not None and math.isfinite(e.north) and math.isfinite(e.east):
            lat, lon = MapProjection(home.lat, home.lon).reproject(e.north, e.east)
            frame, x, y = mi.MAV_FRAME_GLOBAL_RELATIVE_ALT, _e7(lat), _e7(lon)
            z = -e.down if math.isfinite(e.down) else math.nan
        else:
            frame = mi.MAV_FRAME_LOCAL_NED
            x = round(e.north * 1e4) if math.isfinite(e.north) else 0
            y = round(e.east * 1e4) if math.isfinite(e.east) else 0
            z = e.down
    return mavlink2.MAVLink_mission_item_int_message(
        target[0],
        target[1],
        seq,
        frame,
        e.command,
        int(current),
        int(e.autocontinue),
        p1,
        p2,
        p3,
        p4,
        x,
        y,
        z,
        mavlink2.MAV_MISSION_TYPE_MISSION,
    )


def mission_home(home: HomePosition | None, lpos: VehicleLocalPosition | None) -> GeoPoint | None:
    """Where an uploaded mission's global positions are placed: the vehicle's home, failing that where it is (its
    local position reprojected about the estimator's origin), failing that nowhere."""
    if home is not None and home.valid_hpos and home.valid_alt:
        return GeoPoint(home.lat, home.lon, home.alt)
    if lpos is not None and lpos.xy_valid and lpos.z_valid and math.isfinite(lpos.ref_lat):
        lat, lon = MapProjection(lpos.ref_lat, lpos.ref_lon).reproject(lpos.x, lpos.y)
        return GeoPoint(lat, lon, lpos.ref_alt - lpos.z)
    return None


def mission_from_upload(
    items: list[mavlink2.MAVLink_mission_item_int_message], home: GeoPoint | None, source: str
) -> Mission:
    """An uploaded mission, each item converted; raises :class:`ItemRefused` for the first item refused."""
    return Mission(tuple(item_from_mission_item_int(m, home) for m in items), home, source=source)


def download_items(
    msg: MissionMsg | None, result: MissionResult | None
) -> list[mavlink2.MAVLink_mission_item_int_message]:
    """The items a download gets: those of the last ``mission`` message once the navigator has accepted it (its
    ``mission_result`` valid for the same mission id), the current one flagged; none otherwise."""
    if result is None or not result.valid or msg is None or msg.mission_id != result.mission_id:
        return []
    home = mission_from_message(msg).home
    return [
        mission_item_int(entry, seq, home, (0, 0), current=seq == result.seq_current)
        for seq, entry in enumerate(msg.items)
    ]
