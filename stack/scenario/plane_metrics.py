"""How a fixed-wing flight is judged: track, loiter, altitude and airspeed errors and the landing, from the truth.

Everything is measured on the simulator's ground truth about home (:class:`~stack.scenario.autonomy.Frames`):

* a straight leg A→B is judged on its second half (the first half belongs to the turn onto it): the
  cross-track distance from the line, and the altitude and true-airspeed errors there (level flight);
* a turn's overshoot is how far the vehicle went past the next leg's line, on the outside of the turn,
  while flying the first half of that leg;
* a loiter is judged once the vehicle is on its circle (within a fifth of the radius): the radius error;
* the landing is on the runway when the vehicle came to rest within its width of the runway's centre line
  (through home along the takeoff heading) and between its threshold and its end; its touchdown is judged by the
  sink rate at the wheels' first contact (the worst of them, if it bounced).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

from stack.scenario.metrics import rms

Vec2 = tuple[float, float]

ON_CIRCLE_FRACTION = 0.2


class Sample(NamedTuple):
    """One ground-truth sample about home: time, position NED, the true airspeed, and its setpoint."""

    t: float
    position: tuple[float, float, float]
    airspeed: float
    airspeed_sp: float


def _cross(a: Vec2, b: Vec2) -> float:
    return a[0] * b[1] - a[1] * b[0]


def _along_across(a: Vec2, b: Vec2, p: Vec2) -> tuple[float, float, float]:
    """(distance along A→B from A, signed distance to the right of the line, the leg's length)."""
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    u = ((b[0] - a[0]) / length, (b[1] - a[1]) / length)
    ap = (p[0] - a[0], p[1] - a[1])
    return ap[0] * u[0] + ap[1] * u[1], _cross(u, ap), length


class LegErrors(NamedTuple):
    xtrack: list[float]
    altitude: list[float]
    airspeed: list[float]


def leg_errors(samples: Sequence[Sample], a: Vec2, b: Vec2, altitude: float) -> LegErrors:
    """Errors over the second half of leg A→B (samples flown while the leg was the current one)."""
    out = LegErrors([], [], [])
    for s in samples:
        along, across, length = _along_across(a, b, (s.position[0], s.position[1]))
        if 0.5 * length <= along <= length:
            out.xtrack.append(across)
            out.altitude.append(-s.position[2] - altitude)
            if math.isfinite(s.airspeed_sp):
                out.airspeed.append(s.airspeed - s.airspeed_sp)
    return out


def turn_overshoot(samples: Sequence[Sample], previous: Vec2, corner: Vec2, following: Vec2) -> float:
    """How far past the line corner→following the vehicle went on the turn's outside (0 if it never did)."""
    into = (corner[0] - previous[0], corner[1] - previous[1])
    turn = _cross(into, (following[0] - corner[0], following[1] - corner[1]))
    outside = -1.0 if turn > 0.0 else 1.0  # a right turn's outside is the new leg's left
    worst = 0.0
    for s in samples:
        along, across, length = _along_across(corner, following, (s.position[0], s.position[1]))
        if along <= 0.5 * length:
            worst = max(worst, outside * across)
    return worst


def loiter_radius_errors(samples: Sequence[Sample], center: Vec2, radius: float) -> list[float]:
    """|distance to the centre| − radius, from the first time the vehicle is on the circle."""
    errors: list[float] = []
    for s in samples:
        error = math.hypot(s.position[0] - center[0], s.position[1] - center[1]) - radius
        if errors or abs(error) <= ON_CIRCLE_FRACTION * radius:
            errors.append(error)
    return errors


def touchdown_sink(on_ground: Sequence[bool], down_speed: Sequence[float]) -> float:
    """The largest sink rate [m/s] just before the wheels touched after flying (NaN: it never landed)."""
    sinks = [down_speed[i - 1] for i in range(1, len(on_ground)) if on_ground[i] and not on_ground[i - 1]]
    return max(sinks) if sinks else math.nan


def summary(errors: Sequence[float]) -> tuple[float, float]:
    """(RMS, max |e|) — NaN for no samples."""
    if not errors:
        return math.nan, math.nan
    return rms(errors), max(abs(e) for e in errors)
