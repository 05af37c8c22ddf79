"""Mission items: MAVLink mission commands converted to the local NED frame about home.

A :class:`MissionItem` keeps the MAVLink command and frame it came from, its geodetic position when it has
one, and its position in local NED metres about home (north, east, down; NaN where the item leaves the
value to the vehicle, e.g. a takeoff or landing "here"). Angles are radians, times seconds.

Supported commands (MAV_CMD): NAV_WAYPOINT 16, NAV_LOITER_UNLIM 17, NAV_LOITER_TURNS 18, NAV_LOITER_TIME 19,
NAV_RETURN_TO_LAUNCH 20, NAV_LAND 21, NAV_TAKEOFF 22, DO_CHANGE_SPEED 178. Supported frames (MAV_FRAME):
GLOBAL 0 and GLOBAL_INT 5 (altitude AMSL), GLOBAL_RELATIVE_ALT 3 and GLOBAL_RELATIVE_ALT_INT 6 (altitude
above home), MISSION 2 (no position), LOCAL_NED 1 (x north, y east, z down in metres about home).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

from stack.mathlib.geo import MapProjection

NAN = math.nan

MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LOITER_UNLIM = 17
MAV_CMD_NAV_LOITER_TURNS = 18
MAV_CMD_NAV_LOITER_TIME = 19
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
MAV_CMD_DO_CHANGE_SPEED = 178

COMMAND_NAMES: dict[int, str] = {
    MAV_CMD_NAV_WAYPOINT: "waypoint",
    MAV_CMD_NAV_LOITER_UNLIM: "loiter",
    MAV_CMD_NAV_LOITER_TURNS: "loiter_turns",
    MAV_CMD_NAV_LOITER_TIME: "loiter_time",
    MAV_CMD_NAV_RETURN_TO_LAUNCH: "rtl",
    MAV_CMD_NAV_LAND: "land",
    MAV_CMD_NAV_TAKEOFF: "takeoff",
    MAV_CMD_DO_CHANGE_SPEED: "speed",
}

LOITER_COMMANDS = frozenset({MAV_CMD_NAV_LOITER_UNLIM, MAV_CMD_NAV_LOITER_TURNS, MAV_CMD_NAV_LOITER_TIME})
"""Commands that circle a position (a fixed-wing orbits it; a multicopter holds over it)."""
POSITION_COMMANDS = frozenset({MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF}) | LOITER_COMMANDS
"""Commands that fly to a position."""
HERE_COMMANDS = frozenset({MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF})
"""Commands for which a latitude/longitude of 0 or NaN means "where the vehicle is"."""

MAV_FRAME_GLOBAL = 0
MAV_FRAME_LOCAL_NED = 1
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_INT = 5
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT = 6

GLOBAL_AMSL_FRAMES = frozenset({MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT})
GLOBAL_RELATIVE_FRAMES = frozenset({MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})
SUPPORTED_FRAMES = GLOBAL_AMSL_FRAMES | GLOBAL_RELATIVE_FRAMES | {MAV_FRAME_LOCAL_NED, MAV_FRAME_MISSION}


class MissionError(ValueError):
    """A mission file could not be read; the message names the file, the item and the problem."""


@dataclass(frozen=True, slots=True)
class GeoPoint:
    """A geodetic position: latitude, longitude [deg] and altitude AMSL [m]."""

    lat: float
    lon: float
    alt: float


@dataclass(frozen=True, slots=True)
class MissionItem:
    index: int
    """Position in the mission, from 0."""
    command: int
    """MAV_CMD id."""
    frame: int
    """MAV_FRAME the item was given in."""
    north: float
    east: float
    down: float
    """Local NED position about home [m]; NaN where the vehicle's current value is to be used."""
    lat: float = NAN
    lon: float = NAN
    alt: float = NAN
    """Geodetic position as given (alt AMSL for GLOBAL frames, above home for RELATIVE ones); NaN if local."""
    acceptance_radius: float = 0.0
    """Horizontal acceptance radius [m]; 0 uses NAV_ACC_RAD."""
    yaw: float = NAN
    """Heading to hold at the item [rad]; NaN leaves it free."""
    hold_time: float = 0.0
    """Time to stay at the item once reached [s]."""
    speed: float = NAN
    """DO_CHANGE_SPEED: new cruise speed [m/s]; NaN otherwise."""
    autocontinue: bool = True
    loiter_radius: float = NAN
    """Loiter items: the circle's radius [m], positive clockwise, negative counter-clockwise (MAVLink param3);
    NaN uses NAV_LOITER_RAD."""
    loiter_turns: float = NAN
    """LOITER_TURNS: the number of full circles (param1)."""

    @property
    def name(self) -> str:
        return COMMAND_NAMES.get(self.command, str(self.command))

    @property
    def has_position(self) -> bool:
        return self.command in POSITION_COMMANDS

    @property
    def position(self) -> tuple[float, float, float]:
        return (self.north, self.east, self.down)


@dataclass(frozen=True, slots=True)
class Mission:
    """A mission: items in order, the home they are relative to (None for a purely local mission), and
    the file they came from."""

    items: tuple[MissionItem, ...]
    home: GeoPoint | None = None
    source: str = ""

    def __len__(self) -> int:
        return len(self.items)

    def __iter__(self) -> Iterator[MissionItem]:
        return iter(self.items)

    def __getitem__(self, index: int) -> MissionItem:
        return self.items[index]


def about_home(mission: Mission, home: GeoPoint) -> Mission:
    """The mission flown from ``home``: each item's latitude and longitude is a place on the ground and its AMSL
    altitude a height, wherever home was when the mission was planned, as PX4's navigator flies global items at
    their coordinates (home is set again at arming, after the upload). Local items and heights above home stay
    about home."""
    if mission.home == home:
        return mission
    projection = MapProjection(home.lat, home.lon)
    items = []
    for item in mission.items:
        changes: dict[str, float] = {}
        if math.isfinite(item.lat) and math.isfinite(item.lon):
            changes["north"], changes["east"] = projection.project(item.lat, item.lon)
        amsl = item.frame != MAV_FRAME_LOCAL_NED and item.frame not in GLOBAL_RELATIVE_FRAMES
        if amsl and math.isfinite(item.alt) and math.isfinite(item.down):
            changes["down"] = home.alt - item.alt
        items.append(replace(item, **changes) if changes else item)
    return Mission(tuple(items), home, mission.source)


def _number(value: object) -> float:
    """A JSON/CSV parameter as float; None (QGroundControl's NaN) becomes NaN."""
    if value is None:
        return NAN
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{value!r} is not a number")
    return float(value)


def item_from_mavlink(
    index: int,
    command: int,
    frame: int,
    params: Sequence[object],
    autocontinue: bool,
    home: GeoPoint | None,
) -> MissionItem:
    """Convert one MAVLink MISSION_ITEM (command, frame, param1…7) to a :class:`MissionItem`.

    Raises ValueError with the problem (the caller adds the file and item)."""
    if command not in COMMAND_NAMES:
        supported = ", ".join(f"{c} ({n})" for c, n in COMMAND_NAMES.items())
        raise ValueError(f"unsupported command {command} (supported: {supported})")
    if len(params) != 7:
        raise ValueError(f"expected 7 params, got {len(params)}")
    p = [_number(v) for v in params]
    for i, v in enumerate(p):
        if math.isinf(v):
            raise ValueError(f"param{i + 1} is infinite")

    has_yaw = command in POSITION_COMMANDS - LOITER_COMMANDS and math.isfinite(p[3])
    yaw = math.radians(p[3]) if has_yaw else NAN
    hold = 0.0
    radius = 0.0
    speed = NAN
    loiter_radius = NAN
    loiter_turns = NAN
    if command in LOITER_COMMANDS and math.isfinite(p[2]) and p[2] != 0.0:
        loiter_radius = p[2]
    if command == MAV_CMD_NAV_WAYPOINT:
        hold = 0.0 if math.isnan(p[0]) else p[0]
        radius = 0.0 if math.isnan(p[1]) else p[1]
    elif command == MAV_CMD_NAV_LOITER_TIME:
        hold = 0.0 if math.isnan(p[0]) else p[0]
    elif command == MAV_CMD_NAV_LOITER_TURNS:
        loiter_turns = p[0]
        if not (math.isfinite(loiter_turns) and loiter_turns > 0.0):
            raise ValueError(f"loiter turns (param1) must be > 0, got {loiter_turns:g}")
    elif command == MAV_CMD_DO_CHANGE_SPEED:
        speed = p[1] if math.isfinite(p[1]) and p[1] > 0.0 else NAN
    if hold < 0.0:
        raise ValueError(f"hold time {hold:g} s is negative")
    if radius < 0.0:
        raise ValueError(f"acceptance radius {radius:g} m is negative")

    north = east = down = NAN
    lat = lon = alt = NAN
    if command in POSITION_COMMANDS:
        if frame not in SUPPORTED_FRAMES or frame == MAV_FRAME_MISSION:
            raise ValueError(
                f"frame {frame} is not supported for a {COMMAND_NAMES[command]} item "
                "(use 0 global AMSL, 3 global relative altitude or 1 local NED)"
            )
        x, y, z = p[4], p[5], p[6]
        if frame == MAV_FRAME_LOCAL_NED:
            north, east, down = x, y, z
            if command not in HERE_COMMANDS and not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
                raise ValueError("local position (params 5-7) must be given")
        else:
            here = command in HERE_COMMANDS and (math.isnan(x) or math.isnan(y) or (x == 0.0 and y == 0.0))
            if not here:
                if not (math.isfinite(x) and math.isfinite(y)):
                    raise ValueError("latitude/longitude (params 5, 6) must be given")
                if not (-90.0 <= x <= 90.0):
                    raise ValueError(f"latitude {x:g} is outside ±90°")
                if not (-180.0 <= y <= 180.0):
                    raise ValueError(f"longitude {y:g} is outside ±180°")
                if home is None:
                    raise ValueError("a global position needs a home position to convert it to the local frame")
                lat, lon = x, y
                north, east = MapProjection(home.lat, home.lon).project(lat, lon)
            if not math.isfinite(z):
                if command != MAV_CMD_NAV_LAND:
                    raise ValueError("altitude (param 7) must be given")
            else:
                alt = z
                if frame in GLOBAL_RELATIVE_FRAMES:
                    down = -z
                elif home is None:
                    raise ValueError("an AMSL altitude needs a home position to convert it to the local frame")
                else:
                    down = home.alt - z
        if command == MAV_CMD_NAV_LAND:
            down = NAN
    return MissionItem(
        index=index,
        command=command,
        frame=frame,
        north=north,
        east=east,
        down=down,
        lat=lat,
        lon=lon,
        alt=alt,
        acceptance_radius=radius,
        yaw=yaw,
        hold_time=hold,
        speed=speed,
        autocontinue=autocontinue,
        loiter_radius=loiter_radius,
        loiter_turns=loiter_turns,
    )
