"""Rotor control-effectiveness matrix from per-rotor geometry.

Follows PX4 ``control_allocator/VehicleActuatorEffectiveness/ActuatorEffectivenessRotors.cpp``: rotor i
at position p_i [m, FRD, from the centre of gravity] with unit thrust axis a_i (default (0, 0, −1),
thrust up), thrust coefficient CT_i (thrust at full command, CA_ROTORi_CT) and moment ratio KM_i
(CA_ROTORi_KM, positive for a counter-clockwise rotor seen from above) contributes the column

    moment = CT·(p × a) − CT·KM·a        thrust = CT·a

to the 6 × N matrix with rows (roll, pitch, yaw, Fx, Fy, Fz). Setup-time only; numpy.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from stack.mathlib.scalar import FLT_EPSILON
from stack.params import ca
from stack.params.binding import with_defaults
from stack.params.ca import MAX_ROTORS
from stack.params.param import Param

PARAMS: tuple[Param, ...] = ca.ROTOR_PARAMS


def rotor_effectiveness(positions: np.ndarray, axes: np.ndarray, ct: np.ndarray, km: np.ndarray) -> np.ndarray:
    """6 × N effectiveness from N×3 positions, N×3 axes (normalised here) and per-rotor CT and KM.

    A rotor with a zero axis or CT = 0 gets a zero column, as in PX4.
    """
    positions = np.asarray(positions, dtype=float).reshape(-1, 3)
    axes = np.asarray(axes, dtype=float).reshape(-1, 3)
    n = positions.shape[0]
    ct = np.broadcast_to(np.asarray(ct, dtype=float), (n,))
    km = np.broadcast_to(np.asarray(km, dtype=float), (n,))
    b = np.zeros((6, n))
    for i in range(n):
        norm = np.linalg.norm(axes[i])
        if norm <= FLT_EPSILON or abs(ct[i]) <= FLT_EPSILON:
            continue
        axis = axes[i] / norm
        b[0:3, i] = ct[i] * np.cross(positions[i], axis) - ct[i] * km[i] * axis
        b[3:6, i] = ct[i] * axis
    return b


def effectiveness_from_params(params: Mapping[str, object]) -> np.ndarray:
    """6 × CA_ROTOR_COUNT effectiveness from CA_ROTOR* parameters (missing → PX4 defaults)."""
    p = with_defaults(PARAMS, params)
    n = int(p["CA_ROTOR_COUNT"])
    if not 0 <= n <= MAX_ROTORS:
        raise ValueError(f"CA_ROTOR_COUNT must be in [0, {MAX_ROTORS}], got {n}")
    pos = [[float(p[f"CA_ROTOR{i}_P{c}"]) for c in "XYZ"] for i in range(n)]
    axes = [[float(p[f"CA_ROTOR{i}_A{c}"]) for c in "XYZ"] for i in range(n)]
    ct = [float(p[f"CA_ROTOR{i}_CT"]) for i in range(n)]
    km = [float(p[f"CA_ROTOR{i}_KM"]) for i in range(n)]
    return rotor_effectiveness(np.array(pos).reshape(n, 3), np.array(axes).reshape(n, 3), np.array(ct), np.array(km))


def collective_thrust_max(params: Mapping[str, object]) -> float:
    """The collective thrust [N] along −z body with every rotor at full command."""
    return float(-effectiveness_from_params(params)[5].sum())
