"""The runway a fixed-wing vehicle takes off from and lands back on, and where a rest counts as on it.

The runway starts at the takeoff point and runs along the takeoff heading; the navigator lands along it
(touchdown aimed at its start), so a plane at rest a few hundred metres along it, after its roll-out, has
landed where it should: a return is judged by the runway, not by the distance to home.
"""

from __future__ import annotations

import math
from typing import NamedTuple

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]

RUNWAY_HALF_WIDTH_M = 10.0
RUNWAY_THRESHOLD_M = 50.0
"""The runway starts this far before its touchdown point (along the landing direction)."""
RUNWAY_LENGTH_M = 600.0
"""Room for a flare and roll-out past the touchdown point."""


class Runway(NamedTuple):
    """Where the vehicle took off: the start point (local NED) and the heading [rad]."""

    start: Vec3
    heading: float


def on_runway(rest: Vec2, start: Vec2, heading: float, length: float = RUNWAY_LENGTH_M) -> tuple[bool, float, float]:
    """(on the runway, distance along it from ``start``, distance to the right of its centre line) of ``rest``."""
    dn, de = rest[0] - start[0], rest[1] - start[1]
    along = dn * math.cos(heading) + de * math.sin(heading)
    across = -dn * math.sin(heading) + de * math.cos(heading)
    ok = abs(across) <= RUNWAY_HALF_WIDTH_M and -RUNWAY_THRESHOLD_M <= along <= length
    return ok, along, across
