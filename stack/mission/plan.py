"""QGroundControl ``.plan`` files (JSON): reading the mission part and writing a plan QGC can open.

The format (QGC ``PlanMasterController``, plan version 1, mission version 2)::

    {"fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
     "mission": {"version": 2, "firmwareType": 12, "vehicleType": 2, "cruiseSpeed": 15, "hoverSpeed": 5,
                 "globalPlanAltitudeMode": 1, "plannedHomePosition": [lat, lon, alt_amsl],
                 "items": [{"type": "SimpleItem", "command": 16, "frame": 3, "autoContinue": true,
                            "doJumpId": 1, "params": [hold, acc_rad, pass_rad, yaw_deg, lat, lon, alt]}, ...]},
     "geoFence": {"version": 2, "circles": [], "polygons": []},
     "rallyPoints": {"version": 2, "points": []}}

QGC writes ``null`` for a NaN parameter. Complex items (survey, corridor scan, structure scan) are not
supported. Reading converts every item to local NED about the home position: ``plannedHomePosition`` unless
another home is given. Writing puts local items in frame 3 (relative altitude) at the latitude/longitude of
their NED position about home.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from stack.mathlib.geo import MapProjection
from stack.mission.items import (
    GLOBAL_AMSL_FRAMES,
    GLOBAL_RELATIVE_FRAMES,
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
    GeoPoint,
    Mission,
    MissionError,
    MissionItem,
    item_from_mavlink,
)

QGC_FIRMWARE_PX4 = 12
MAV_TYPE_QUADROTOR = 2
QGC_ALTITUDE_MODE_RELATIVE = 1
QGC_ALTITUDE_MODE_ABSOLUTE = 2
DEFAULT_CRUISE_SPEED = 15.0
DEFAULT_HOVER_SPEED = 5.0


def _home_from_json(path: str, value: object) -> GeoPoint:
    if not isinstance(value, list) or len(value) != 3:
        raise MissionError(f"{path}: mission.plannedHomePosition must be [latitude, longitude, altitude]")
    try:
        lat, lon, alt = (float(v) for v in value)
    except (TypeError, ValueError):
        raise MissionError(f"{path}: mission.plannedHomePosition must hold three numbers, got {value!r}") from None
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and math.isfinite(alt)):
        raise MissionError(f"{path}: mission.plannedHomePosition {value!r} is not a valid position")
    return GeoPoint(lat, lon, alt)


def parse_plan(text: str, source: str = "<plan>", home: GeoPoint | None = None) -> Mission:
    """Parse the text of a ``.plan`` file; ``home`` overrides its plannedHomePosition."""
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise MissionError(f"{source}: not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})") from None
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        raise MissionError(f'{source}: not a QGroundControl plan (expected "fileType": "Plan")')
    mission = doc.get("mission")
    if not isinstance(mission, dict):
        raise MissionError(f'{source}: the plan has no "mission" object')
    raw_items = mission.get("items")
    if not isinstance(raw_items, list):
        raise MissionError(f"{source}: mission.items must be a list")
    if home is None and "plannedHomePosition" in mission:
        home = _home_from_json(source, mission["plannedHomePosition"])

    items: list[MissionItem] = []
    for index, raw in enumerate(raw_items):
        where = f"{source}: mission item {index}"
        if not isinstance(raw, dict):
            raise MissionError(f"{where}: expected an object, got {type(raw).__name__}")
        kind = raw.get("type")
        if kind == "ComplexItem":
            name = raw.get("complexItemType", "complex item")
            raise MissionError(f"{where}: {name} items are not supported (only SimpleItem)")
        if kind != "SimpleItem":
            raise MissionError(f'{where}: unknown item type {kind!r} (expected "SimpleItem")')
        command, frame = raw.get("command"), raw.get("frame")
        if isinstance(command, bool) or not isinstance(command, int):
            raise MissionError(f"{where}: command must be an integer MAV_CMD, got {command!r}")
        if isinstance(frame, bool) or not isinstance(frame, int):
            raise MissionError(f"{where}: frame must be an integer MAV_FRAME, got {frame!r}")
        params = raw.get("params")
        if not isinstance(params, list):
            raise MissionError(f"{where}: params must be a list of 7 numbers")
        try:
            items.append(
                item_from_mavlink(len(items), command, frame, params, bool(raw.get("autoContinue", True)), home)
            )
        except ValueError as e:
            raise MissionError(f"{where}: {e}") from None
    return Mission(tuple(items), home, source)


def _json_number(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _radius(item: MissionItem) -> float:
    return item.loiter_radius if math.isfinite(item.loiter_radius) else 0.0


def _item_json(item: MissionItem, home: GeoPoint | None, source: str) -> dict[str, object]:
    frame = MAV_FRAME_MISSION
    lat = lon = alt = math.nan
    altitude_mode = None
    if item.has_position:
        if item.frame in GLOBAL_AMSL_FRAMES | GLOBAL_RELATIVE_FRAMES:
            frame, lat, lon, alt = item.frame, item.lat, item.lon, item.alt
            if math.isnan(lat) and home is not None and math.isfinite(item.north):
                lat, lon = MapProjection(home.lat, home.lon).reproject(item.north, item.east)
        else:
            frame = MAV_FRAME_GLOBAL_RELATIVE_ALT
            if math.isfinite(item.north) and math.isfinite(item.east):
                if home is None:
                    raise MissionError(f"{source}: writing a .plan needs a home position for local item {item.index}")
                lat, lon = MapProjection(home.lat, home.lon).reproject(item.north, item.east)
            alt = -item.down
        altitude_mode = QGC_ALTITUDE_MODE_ABSOLUTE if frame in GLOBAL_AMSL_FRAMES else QGC_ALTITUDE_MODE_RELATIVE

    yaw_deg = math.degrees(item.yaw) if math.isfinite(item.yaw) else math.nan
    if item.command == MAV_CMD_NAV_WAYPOINT:
        params = [item.hold_time, item.acceptance_radius, 0.0, yaw_deg, lat, lon, alt]
    elif item.command == MAV_CMD_NAV_LOITER_TIME:
        params = [item.hold_time, 0.0, _radius(item), 0.0, lat, lon, alt]
    elif item.command == MAV_CMD_NAV_LOITER_TURNS:
        params = [item.loiter_turns, 0.0, _radius(item), 0.0, lat, lon, alt]
    elif item.command == MAV_CMD_NAV_LOITER_UNLIM:
        params = [0.0, 0.0, _radius(item), yaw_deg, lat, lon, alt]
    elif item.command == MAV_CMD_DO_CHANGE_SPEED:
        params = [1.0, item.speed if math.isfinite(item.speed) else -1.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    elif item.has_position:
        params = [0.0, 0.0, 0.0, yaw_deg, lat, lon, alt]
    else:
        params = [0.0] * 7
    out: dict[str, object] = {
        "autoContinue": item.autocontinue,
        "command": item.command,
        "doJumpId": item.index + 1,
        "frame": frame,
        "params": [_json_number(v) for v in params],
        "type": "SimpleItem",
    }
    if altitude_mode is not None:
        out["AMSLAltAboveTerrain"] = None
        out["Altitude"] = _json_number(alt)
        out["AltitudeMode"] = altitude_mode
    return out


def plan_json(mission: Mission, home: GeoPoint | None = None) -> dict[str, object]:
    """The ``.plan`` document for a mission; ``home`` defaults to the mission's own."""
    home = home or mission.home
    source = mission.source or "<mission>"
    planned_home = [home.lat, home.lon, home.alt] if home is not None else [0.0, 0.0, 0.0]
    return {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": DEFAULT_CRUISE_SPEED,
            "firmwareType": QGC_FIRMWARE_PX4,
            "globalPlanAltitudeMode": QGC_ALTITUDE_MODE_RELATIVE,
            "hoverSpeed": DEFAULT_HOVER_SPEED,
            "items": [_item_json(item, home, source) for item in mission],
            "plannedHomePosition": planned_home,
            "vehicleType": MAV_TYPE_QUADROTOR,
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }


def write_plan(path: str | Path, mission: Mission, home: GeoPoint | None = None) -> None:
    """Write ``mission`` as a QGroundControl ``.plan`` file."""
    Path(path).write_text(json.dumps(plan_json(mission, home), indent=4) + "\n", encoding="utf-8")
