"""Text waypoint lists: the stack's simple local list, and the QGC WPL 110 format.

**Simple list** (our format). One item per line, local NED metres about home; ``#`` starts a comment;
``-`` or ``nan`` leaves an optional value unset::

    # survey of the east field
    takeoff 5                  # climb to 5 m above home            takeoff ALT [YAW_DEG]
    10 0 -5                    # waypoint north east down           N E D [YAW_DEG] [HOLD_S] [RADIUS_M]
    waypoint 10 10 -5 90 2     # the same with the keyword (also "wp")
    speed 3                    # cruise speed from here on [m/s]
    loiter 0 10 -5             # hold there until told otherwise    loiter N E D [YAW_DEG]
    land                       # land where the vehicle is          land [N E]
    rtl                        # return to launch (also "return")

**QGC WPL 110** (QGroundControl's and Mission Planner's ``.waypoints`` text export): a ``QGC WPL 110``
header, then one tab-separated line per item ``seq current frame command p1 p2 p3 p4 x y z autocontinue``.
Item 0 is the home position (frame 0, AMSL); the mission is the items after it.
"""

from __future__ import annotations

import math

from stack.mathlib.geo import MapProjection
from stack.mission.items import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_LOCAL_NED,
    MAV_FRAME_MISSION,
    GeoPoint,
    Mission,
    MissionError,
    MissionItem,
    item_from_mavlink,
)

WPL_HEADER = "QGC WPL 110"
NAN = math.nan


def _value(token: str, what: str) -> float:
    if token in ("-", "nan", "NaN"):
        return NAN
    try:
        value = float(token)
    except ValueError:
        raise ValueError(f"{what} must be a number, got {token!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{what} must be finite, got {token!r}")
    return value


def _required(tokens: list[str], names: tuple[str, ...], optional: tuple[str, ...]) -> list[float]:
    if not len(names) <= len(tokens) <= len(names) + len(optional):
        usage = " ".join(names + tuple(f"[{o}]" for o in optional))
        raise ValueError(f"expected {usage}, got {len(tokens)} value(s)")
    values = [_value(t, n) for t, n in zip(tokens, names + optional, strict=False)]
    for value, name in zip(values, names, strict=False):
        if math.isnan(value):
            raise ValueError(f"{name} must be given")
    return values + [NAN] * (len(names) + len(optional) - len(values))


def _simple_item(index: int, keyword: str, args: list[str]) -> MissionItem:
    if keyword in ("waypoint", "wp"):
        n, e, d, yaw, hold, radius = _required(args, ("north", "east", "down"), ("yaw_deg", "hold_s", "radius_m"))
        hold = 0.0 if math.isnan(hold) else hold
        radius = 0.0 if math.isnan(radius) else radius
        if hold < 0.0 or radius < 0.0:
            raise ValueError("hold time and acceptance radius must not be negative")
        return MissionItem(
            index,
            MAV_CMD_NAV_WAYPOINT,
            MAV_FRAME_LOCAL_NED,
            n,
            e,
            d,
            acceptance_radius=radius,
            yaw=_radians(yaw),
            hold_time=hold,
        )
    if keyword == "takeoff":
        altitude, yaw = _required(args, ("altitude",), ("yaw_deg",))
        if altitude <= 0.0:
            raise ValueError(f"takeoff altitude must be above home, got {altitude:g} m")
        return MissionItem(index, MAV_CMD_NAV_TAKEOFF, MAV_FRAME_LOCAL_NED, NAN, NAN, -altitude, yaw=_radians(yaw))
    if keyword == "loiter":
        n, e, d, yaw = _required(args, ("north", "east", "down"), ("yaw_deg",))
        return MissionItem(index, MAV_CMD_NAV_LOITER_UNLIM, MAV_FRAME_LOCAL_NED, n, e, d, yaw=_radians(yaw))
    if keyword == "land":
        if args:
            n, e = _required(args, ("north", "east"), ())
        else:
            n = e = NAN
        return MissionItem(index, MAV_CMD_NAV_LAND, MAV_FRAME_LOCAL_NED, n, e, NAN)
    if keyword in ("rtl", "return"):
        _required(args, (), ())
        return MissionItem(index, MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_FRAME_MISSION, NAN, NAN, NAN)
    if keyword == "speed":
        (speed,) = _required(args, ("speed",), ())
        if speed <= 0.0:
            raise ValueError(f"speed must be positive, got {speed:g} m/s")
        return MissionItem(index, MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION, NAN, NAN, NAN, speed=speed)
    raise ValueError(f"unknown item {keyword!r} (expected N E D, waypoint, takeoff, loiter, land, rtl or speed)")


def _radians(degrees: float) -> float:
    return math.radians(degrees) if math.isfinite(degrees) else NAN


def _with_geodetic(item: MissionItem, home: GeoPoint | None) -> MissionItem:
    """Fill lat/lon from the local position when a home is known (for writing .plan files)."""
    if home is None or not (math.isfinite(item.north) and math.isfinite(item.east)):
        return item
    lat, lon = MapProjection(home.lat, home.lon).reproject(item.north, item.east)
    alt = home.alt - item.down if math.isfinite(item.down) else NAN
    return MissionItem(
        item.index,
        item.command,
        item.frame,
        item.north,
        item.east,
        item.down,
        lat,
        lon,
        alt,
        item.acceptance_radius,
        item.yaw,
        item.hold_time,
        item.speed,
        item.autocontinue,
    )


def parse_waypoint_list(text: str, source: str = "<waypoints>", home: GeoPoint | None = None) -> Mission:
    """Parse the simple local waypoint list (see the module docstring)."""
    items: list[MissionItem] = []
    for line_no, line in enumerate(text.splitlines(), start=1):
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        keyword = tokens[0].lower()
        args = tokens[1:]
        if keyword[0].isdigit() or keyword[0] in "+-.":
            keyword, args = "waypoint", tokens
        try:
            items.append(_with_geodetic(_simple_item(len(items), keyword, args), home))
        except ValueError as e:
            raise MissionError(f"{source}: line {line_no} (item {len(items)}): {e}") from None
    if not items:
        raise MissionError(f"{source}: no mission items")
    return Mission(tuple(items), home, source)


def parse_wpl(text: str, source: str = "<waypoints>", home: GeoPoint | None = None) -> Mission:
    """Parse a QGC WPL 110 file; item 0 is home unless ``home`` is given."""
    lines = text.splitlines()
    if not lines or not lines[0].startswith("QGC WPL"):
        raise MissionError(f"{source}: missing the '{WPL_HEADER}' header")
    if lines[0].split()[-1] != "110":
        raise MissionError(f"{source}: unsupported version {lines[0]!r} (expected '{WPL_HEADER}')")
    rows: list[tuple[int, list[str]]] = [
        (line_no, line.split()) for line_no, line in enumerate(lines[1:], start=2) if line.strip()
    ]
    if not rows:
        raise MissionError(f"{source}: no home line")
    items: list[MissionItem] = []
    for position, (line_no, fields) in enumerate(rows):
        where = f"{source}: line {line_no}"
        if len(fields) != 12:
            raise MissionError(f"{where}: expected 12 tab-separated fields, got {len(fields)}")
        try:
            seq, _current, frame, command = (int(f) for f in fields[:4])
            params = [float(f) for f in fields[4:11]]
            autocontinue = bool(int(fields[11]))
        except ValueError:
            raise MissionError(f"{where}: fields must be numbers") from None
        if seq != position:
            raise MissionError(f"{where}: sequence number {seq}, expected {position}")
        if position == 0:
            if home is None:
                home = GeoPoint(params[4], params[5], params[6])
            continue
        try:
            items.append(item_from_mavlink(len(items), command, frame, params, autocontinue, home))
        except ValueError as e:
            raise MissionError(f"{where} (item {len(items)}): {e}") from None
    if not items:
        raise MissionError(f"{source}: no mission items after the home line")
    return Mission(tuple(items), home, source)
