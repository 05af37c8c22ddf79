"""Fixed-wing control allocation: forward motors and control surfaces (CA_AIRFRAME 1).

Follows PX4 ``control_allocator``: ``ActuatorEffectivenessFixedWing`` puts the CA_ROTOR* motors first, each
pushing along body +x (``ActuatorEffectivenessRotors::AxisConfiguration::FixedForward``, no propeller torque),
then the control surfaces of ``ActuatorEffectivenessControlSurfaces``, surface i's column being its torque at full
deflection (CA_SV_CS<i>_TRQ_R/P/Y; none for flaps, airbrakes, the steering wheel and spoilers). A plane is allocated
by the plain pseudo-inverse (``ControlAllocationPseudoInverse``, no desaturation), normalised on the thrust axes only
(the torque is not: a surface with unit torque moves by the torque setpoint), and the commands are clipped: motors to
[0, 1], surfaces to [−1, 1]. With the default plane (one motor, aileron, elevator, rudder) that is motor = thrust x,
aileron = torque x, elevator = torque y, rudder = torque z.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3
from stack.mixer.allocation import (
    ACHIEVED_TOLERANCE,
    SATURATION_LOWER,
    SATURATION_OK,
    SATURATION_UPPER,
    WEAK_ROW_THRESHOLD,
    normalized_allocation,
)
from stack.mixer.effectiveness import rotor_effectiveness
from stack.params import ca
from stack.params.binding import combine, with_defaults
from stack.params.ca import MAX_ROTORS, MAX_SURFACES, SURFACE_TYPES_WITHOUT_TORQUE
from stack.params.param import Param

PARAMS: tuple[Param, ...] = ca.SURFACE_PARAMS
_GEOMETRY: tuple[Param, ...] = combine(ca.ROTOR_PARAMS, ca.SURFACE_PARAMS)

FORWARD = (1.0, 0.0, 0.0)
"""A fixed-wing motor's thrust axis (body +x)."""
MOTOR_MIN = 0.0
MOTOR_MAX = 1.0
SERVO_MIN = -1.0
SERVO_MAX = 1.0


def surface_torques(params: Mapping[str, object]) -> np.ndarray:
    """CA_SV_CS_COUNT × 3 torques (roll, pitch, yaw) at full deflection from the CA_SV_CS* parameters."""
    p = with_defaults(_GEOMETRY, params)
    n = int(p["CA_SV_CS_COUNT"])
    if not 0 <= n <= MAX_SURFACES:
        raise ValueError(f"CA_SV_CS_COUNT must be in [0, {MAX_SURFACES}], got {n}")
    torques = np.zeros((n, 3))
    for i in range(n):
        if int(p[f"CA_SV_CS{i}_TYPE"]) not in SURFACE_TYPES_WITHOUT_TORQUE:
            torques[i] = [float(p[f"CA_SV_CS{i}_TRQ_{axis}"]) for axis in "RPY"]
    return torques


def fixed_wing_effectiveness(params: Mapping[str, object]) -> np.ndarray:
    """6 × (CA_ROTOR_COUNT + CA_SV_CS_COUNT) effectiveness: the forward motors (CA_ROTOR<i>_PX/PY/PZ, CT; the axis
    and KM parameters do not apply), then the surfaces."""
    p = with_defaults(_GEOMETRY, params)
    n = int(p["CA_ROTOR_COUNT"])
    if not 0 <= n <= MAX_ROTORS:
        raise ValueError(f"CA_ROTOR_COUNT must be in [0, {MAX_ROTORS}], got {n}")
    positions = np.array([[float(p[f"CA_ROTOR{i}_P{c}"]) for c in "XYZ"] for i in range(n)]).reshape(n, 3)
    ct = np.array([float(p[f"CA_ROTOR{i}_CT"]) for i in range(n)])
    motors = rotor_effectiveness(positions, np.tile(FORWARD, (n, 1)), ct, np.zeros(n))
    torques = surface_torques(p)
    surfaces = np.vstack([torques.T, np.zeros((3, torques.shape[0]))])
    return np.hstack([motors, surfaces])


class FixedWingAllocation(NamedTuple):
    """One allocation (control_allocator_status content plus the commands)."""

    motors: tuple[float, ...]
    """Motor commands (normalised thrust) in [0, 1]."""
    servos: tuple[float, ...]
    """Control-surface commands in [−1, 1]."""
    unallocated_torque: Vec3
    unallocated_thrust: Vec3
    torque_achieved: bool
    thrust_achieved: bool
    actuator_saturation: tuple[int, ...]
    """Per actuator, motors first: 0 ok, +2 at maximum, −2 at minimum."""


class FixedWingAllocator:
    """Pseudo-inverse allocation for forward motors and control surfaces."""

    __slots__ = ("_b", "_lower", "_mix", "_motors", "_scale", "_upper")

    def __init__(self, effectiveness: np.ndarray, num_motors: int) -> None:
        b = np.array(effectiveness, dtype=float).reshape(6, -1)
        if not 0 <= num_motors <= b.shape[1]:
            raise ValueError(f"{num_motors} motors among {b.shape[1]} actuators")
        b[np.all(np.abs(b) <= WEAK_ROW_THRESHOLD, axis=1)] = 0.0
        mix, scale = normalized_allocation(b, normalize_rpy=False)
        self._motors = num_motors
        self._b = tuple(tuple(float(x) for x in row) for row in b)
        self._mix = tuple(tuple(float(x) for x in row) for row in mix)
        self._scale = tuple(float(s) for s in scale)
        n = b.shape[1]
        self._lower = tuple(MOTOR_MIN if i < num_motors else SERVO_MIN for i in range(n))
        self._upper = tuple(MOTOR_MAX if i < num_motors else SERVO_MAX for i in range(n))

    @classmethod
    def from_params(cls, params: Mapping[str, object]) -> FixedWingAllocator:
        p = with_defaults(_GEOMETRY, params)
        return cls(fixed_wing_effectiveness(p), int(p["CA_ROTOR_COUNT"]))  # type: ignore[call-overload]

    @property
    def num_motors(self) -> int:
        return self._motors

    @property
    def num_surfaces(self) -> int:
        return len(self._mix) - self._motors

    @property
    def mix(self) -> np.ndarray:
        """The N × 6 allocation matrix (thrust columns normalised)."""
        return np.array(self._mix)

    def allocate(self, torque: Vec3, thrust: Vec3) -> FixedWingAllocation:
        """Commands for a normalised torque (x roll, y pitch, z yaw) and body thrust (x forward)."""
        setpoint = (*torque, *thrust)
        u = [
            min(max(sum(m * c for m, c in zip(row, setpoint, strict=True)), lo), hi)
            for row, lo, hi in zip(self._mix, self._lower, self._upper, strict=True)
        ]
        allocated = [sum(b * x for b, x in zip(row, u, strict=True)) * s
                     for row, s in zip(self._b, self._scale, strict=True)]
        un = [sp - a for sp, a in zip(setpoint, allocated, strict=True)]
        saturation = tuple(
            SATURATION_UPPER if x > hi - FLT_EPSILON else SATURATION_LOWER if x < lo + FLT_EPSILON else SATURATION_OK
            for x, lo, hi in zip(u, self._lower, self._upper, strict=True)
        )
        k = self._motors
        return FixedWingAllocation(
            tuple(u[:k]),
            tuple(u[k:]),
            (un[0], un[1], un[2]),
            (un[3], un[4], un[5]),
            un[0] * un[0] + un[1] * un[1] + un[2] * un[2] < ACHIEVED_TOLERANCE,
            un[3] * un[3] + un[4] * un[4] + un[5] * un[5] < ACHIEVED_TOLERANCE,
            saturation,
        )
