"""Load a mission file whatever its format: QGroundControl ``.plan`` (JSON), QGC WPL 110 or the stack's
simple waypoint list — decided by the content, not the file name."""

from __future__ import annotations

from pathlib import Path

from stack.mission.items import GeoPoint, Mission, MissionError
from stack.mission.plan import parse_plan
from stack.mission.waypoints import parse_waypoint_list, parse_wpl


def load_mission(path: str | Path, home: GeoPoint | None = None) -> Mission:
    """Read a mission file and convert its items to local NED about home.

    ``home`` overrides the file's own home (a .plan's plannedHomePosition, a WPL file's item 0); a simple
    waypoint list is already local and uses ``home`` only to fill in latitudes and longitudes.
    Raises :class:`MissionError` naming the file, the item and the problem."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise MissionError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise MissionError(f"{path}: not a text file") from None
    start = text.lstrip()
    if start.startswith("{"):
        return parse_plan(text, str(path), home)
    if start.startswith("QGC WPL"):
        return parse_wpl(text, str(path), home)
    return parse_waypoint_list(text, str(path), home)
