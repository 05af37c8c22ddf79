"""3-vectors as plain tuples of floats.

Control and estimation loops handle a handful of 3-vectors per step; plain tuples and
scalar arithmetic are several times faster than numpy at that size in CPython.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]

ZERO3: Vec3 = (0.0, 0.0, 0.0)
NAN3: Vec3 = (math.nan, math.nan, math.nan)


def add(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a: Vec3, s: float) -> Vec3:
    return (a[0] * s, a[1] * s, a[2] * s)


def mul(a: Vec3, b: Vec3) -> Vec3:
    """Element-wise product."""
    return (a[0] * b[0], a[1] * b[1], a[2] * b[2])


def dot(a: Vec3, b: Vec3) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a: Vec3) -> float:
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def normalized(a: Vec3) -> Vec3:
    n = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    if n == 0.0:
        return ZERO3
    return (a[0] / n, a[1] / n, a[2] / n)


def neg(a: Vec3) -> Vec3:
    return (-a[0], -a[1], -a[2])


def is_finite(a: Vec3) -> bool:
    return math.isfinite(a[0]) and math.isfinite(a[1]) and math.isfinite(a[2])


def constrain(a: Vec3, lo: Vec3, hi: Vec3) -> Vec3:
    return (
        min(max(a[0], lo[0]), hi[0]),
        min(max(a[1], lo[1]), hi[1]),
        min(max(a[2], lo[2]), hi[2]),
    )


def nan_to_zero(a: Vec3) -> Vec3:
    return (
        a[0] if math.isfinite(a[0]) else 0.0,
        a[1] if math.isfinite(a[1]) else 0.0,
        a[2] if math.isfinite(a[2]) else 0.0,
    )


def line_crossing_point(a: Vec3, b: Vec3, position: Vec3, distance: float) -> Vec3:
    """Point on the line A→B at ``distance`` from position, ahead along A→B (PX4 ``_getL1Point``).

    The foot of the perpendicular from position, moved √(distance² − d⊥²) toward B; the foot
    itself when the line is farther than ``distance``. A zero-length leg returns A.
    """
    ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    n = math.sqrt(ux * ux + uy * uy + uz * uz)
    if n > 0.0:
        ux, uy, uz = ux / n, uy / n, uz / n
    along = (position[0] - a[0]) * ux + (position[1] - a[1]) * uy + (position[2] - a[2]) * uz
    cx, cy, cz = a[0] + ux * along, a[1] + uy * along, a[2] + uz * along
    dx, dy, dz = cx - position[0], cy - position[1], cz - position[2]
    cross_track = math.sqrt(dx * dx + dy * dy + dz * dz)
    ahead = math.sqrt(distance * distance - cross_track * cross_track) if distance > cross_track else 0.0
    return (cx + ahead * ux, cy + ahead * uy, cz + ahead * uz)
