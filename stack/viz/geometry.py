"""The vehicle drawn in the 3D view: rotor hubs from the ``CA_ROTOR*`` parameters, or a generic X quad.

Plain tuples and functions, no Rerun: the logger turns them into line strips and boxes.
Positions are body FRD metres, like PX4's ``CA_ROTORi_PX/PY/PZ``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from stack.mathlib.vector import Vec3
from stack.params.param import ParamValue

# PX4's quadrotor X numbering (motor 1 front-right, 2 rear-left, 3 front-left, 4 rear-right), with
# the SIH quad's 0.2 m hub offsets.
GENERIC_QUAD_X: tuple[Vec3, ...] = (
    (0.2, 0.2, 0.0),
    (-0.2, -0.2, 0.0),
    (0.2, -0.2, 0.0),
    (-0.2, 0.2, 0.0),
)
CIRCLE_SEGMENTS = 16


def rotors_from_params(params: Mapping[str, ParamValue]) -> tuple[Vec3, ...] | None:
    """Rotor hub positions from a control allocator's parameter values, or None if it declares no rotor.

    Reads ``CA_ROTOR_COUNT`` and ``CA_ROTORi_PX``/``PY``/``PZ`` (PX4 control allocation, m, body FRD).
    """
    try:
        count = int(params["CA_ROTOR_COUNT"])
        rotors = tuple(
            (float(params[f"CA_ROTOR{i}_PX"]), float(params[f"CA_ROTOR{i}_PY"]), float(params[f"CA_ROTOR{i}_PZ"]))
            for i in range(count)
        )
    except (KeyError, TypeError, ValueError):
        return None
    return rotors or None


def disc_radius(rotors: Sequence[Vec3]) -> float:
    """Rotor disc radius for drawing: 40 % of the shortest hub-to-hub distance, so discs never overlap."""
    shortest = min((math.dist(a, b) for i, a in enumerate(rotors) for b in rotors[i + 1 :]), default=0.5)
    return 0.4 * shortest if shortest > 0.0 else 0.1


def rotor_disc(center: Vec3, radius: float, segments: int = CIRCLE_SEGMENTS) -> list[Vec3]:
    """A closed circle in the body x-y plane around a rotor hub (the rotor disc outline)."""
    cx, cy, cz = center
    step = 2.0 * math.pi / segments
    return [(cx + radius * math.cos(k * step), cy + radius * math.sin(k * step), cz) for k in range(segments + 1)]
