"""Checks a mission must pass before the navigator accepts it (PX4 navigator ``MissionFeasibilityChecker``).

A mission is refused, with the item and the reason, when it is empty or has more items than a mission may
have (``stack.mission.transfer.MAX_ITEMS``), when an item that flies to a position has no usable position, when
a waypoint lies outside the geofence cylinder about home (GF_MAX_HOR_DIST, GF_MAX_VER_DIST; 0 disables a limit),
when an item follows a landing, or when a position lies further than MIS_DIST_1WP from home (the first waypoint)
or MIS_DIST_WPS from the previous one (PX4's sanity limits against a mistyped coordinate).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from stack.mission.items import MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF, Mission
from stack.mission.transfer import too_many_items
from stack.params.binding import ParamSet
from stack.params.param import Param


class FeasibilityParams(ParamSet):
    """The distances a mission may span (MIS_DIST_*) and the geofence it must stay within."""

    mis_dist_1wp: float
    mis_dist_wps: float
    gf_max_hor_dist: float
    gf_max_ver_dist: float


PARAMS: tuple[Param, ...] = FeasibilityParams.PARAMS


def mission_problem(mission: Mission, params: Mapping[str, object]) -> str:
    """Why the mission cannot be flown, or "" when it can. Positions are local NED about home."""
    p = FeasibilityParams.from_params(params)
    if len(mission) == 0:
        return "the mission has no items"
    too_many = too_many_items(len(mission))
    if too_many:
        return too_many
    max_hor, max_ver = p.gf_max_hor_dist, p.gf_max_ver_dist
    first_limit, leg_limit = p.mis_dist_1wp, p.mis_dist_wps
    previous: tuple[float, float] | None = None
    after_landing = False
    for item in mission:
        where = f"item {item.index} ({item.name})"
        if after_landing:
            return f"{where} follows a landing"
        if not item.has_position:
            continue
        here = item.command in (MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF)
        if not here and not (math.isfinite(item.north) and math.isfinite(item.east) and math.isfinite(item.down)):
            return f"{where} has no position"
        if math.isfinite(item.north) and math.isfinite(item.east):
            distance = math.hypot(item.north, item.east)
            if max_hor > 0.0 and distance > max_hor:
                return f"{where} is {distance:.1f} m from home, outside the geofence (GF_MAX_HOR_DIST {max_hor:g} m)"
            if previous is None and first_limit > 0.0 and distance > first_limit:
                return f"{where} is {distance:.1f} m from home, beyond MIS_DIST_1WP {first_limit:g} m"
            if previous is not None and leg_limit > 0.0:
                leg = math.hypot(item.north - previous[0], item.east - previous[1])
                if leg > leg_limit:
                    return f"{where} is {leg:.1f} m from the previous waypoint, beyond MIS_DIST_WPS {leg_limit:g} m"
            previous = (item.north, item.east)
        if math.isfinite(item.down) and max_ver > 0.0 and -item.down > max_ver:
            return f"{where} is {-item.down:.1f} m above home, above the geofence (GF_MAX_VER_DIST {max_ver:g} m)"
        after_landing = item.command == MAV_CMD_NAV_LAND
    return ""
