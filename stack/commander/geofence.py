"""The cylindrical geofence about home (PX4 navigator ``Geofence``: GF_MAX_HOR_DIST, GF_MAX_VER_DIST).

PX4 checks the horizontal distance from home and the height above home against the two limits (0 disables
a limit) and reports a breach; the commander's failsafe then applies GF_ACTION. Positions here are local
NED metres, so the height above home is ``home_z − z``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import IntEnum

from stack.params.binding import ParamSet
from stack.params.param import Param


class GeofenceAction(IntEnum):
    """GF_ACTION values (PX4 ``geofence_violation_action``)."""

    NONE = 0
    WARNING = 1
    HOLD = 2
    RETURN = 3
    TERMINATE = 4
    LAND = 5


class GeofenceParams(ParamSet):
    """The fence's action and its horizontal and vertical distances from home."""

    gf_action: int
    gf_max_hor_dist: float
    gf_max_ver_dist: float


PARAMS: tuple[Param, ...] = GeofenceParams.PARAMS


class CylinderGeofence:
    """A vertical cylinder of radius GF_MAX_HOR_DIST and height GF_MAX_VER_DIST standing on home."""

    __slots__ = ("action", "max_hor_dist", "max_ver_dist")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = GeofenceParams.from_params(params)
        self.action = GeofenceAction(p.gf_action)
        self.max_hor_dist = p.gf_max_hor_dist
        self.max_ver_dist = p.gf_max_ver_dist

    @property
    def enabled(self) -> bool:
        return self.max_hor_dist > 0.0 or self.max_ver_dist > 0.0

    def violation(self, home: tuple[float, float, float], north: float, east: float, down: float) -> str:
        """Why (north, east, down) is outside the fence about ``home`` (local NED), or "" if it is inside.

        A NaN coordinate is not checked (e.g. a target that keeps the current altitude)."""
        if self.max_hor_dist > 0.0 and math.isfinite(north) and math.isfinite(east):
            distance = math.hypot(north - home[0], east - home[1])
            if distance > self.max_hor_dist:
                return f"{distance:.1f} m from home, beyond GF_MAX_HOR_DIST {self.max_hor_dist:g} m"
        if self.max_ver_dist > 0.0 and math.isfinite(down):
            height = home[2] - down
            if height > self.max_ver_dist:
                return f"{height:.1f} m above home, beyond GF_MAX_VER_DIST {self.max_ver_dist:g} m"
        return ""

    def inside(self, home: tuple[float, float, float], north: float, east: float, down: float) -> bool:
        return not self.violation(home, north, east, down)
