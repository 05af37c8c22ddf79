"""Multirotor control allocation: normalised torque and thrust setpoints → motor commands in [0, 1].

Follows PX4 ``control_allocator``: the pseudo-inverse with multirotor RPY normalisation
(``ControlAllocationPseudoInverse.cpp``), sequential desaturation with MC_AIRMODE
(``ControlAllocationSequentialDesaturation.cpp``), the weak-row zeroing of the effectiveness matrix and
the status of ``ControlAllocator.cpp`` (allocated/unallocated control, achieved flags, actuator
saturation).

One departure: with yaw airmode (MC_AIRMODE 2) yaw may raise the collective thrust to fit, as in PX4's
``mixAirmodeRPY``, but lowers it only within the minimum yaw margin, as ``mixYaw`` does without yaw airmode.
PX4 lowers it as far as yaw asks, so at full thrust (a downdraft at full tilt) a heading correction took
the thrust that held the height.

After normalisation the torque setpoint is in "motor command units": CT and the arm length cancel, so
for a quad X u_i = m_r·τx + m_p·τy + m_y·τz − T_z with |m_r| = |m_p| = 0.7071 and |m_y| = 1.
The matrix work is numpy at setup; ``allocate`` is plain Python over the (≤ 12) motors.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3
from stack.mixer.effectiveness import effectiveness_from_params
from stack.msg.system import VehicleLandDetected
from stack.params.binding import ParamSet
from stack.params.param import Param


class AllocatorParams(ParamSet):
    mc_airmode: int


PARAMS: tuple[Param, ...] = AllocatorParams.PARAMS

WEAK_ROW_THRESHOLD = 0.05
"""An effectiveness row whose entries are all at most this is zeroed (the axis is not controlled)."""
MIX_ZERO_THRESHOLD = 1e-3
"""Normalised allocation entries smaller than this are set to 0."""
DESATURATION_MIN_ENTRY = 0.2
"""Actuators with less effect than this along a desaturation vector are not used to desaturate."""
MINIMUM_YAW_MARGIN = 0.15
"""Extra headroom (fraction of the range) allowed above the maximum while desaturating yaw."""
ACHIEVED_TOLERANCE = 1e-6
"""A setpoint counts as achieved when ‖unallocated‖² is below this."""
ACTUATOR_MIN = 0.0
ACTUATOR_MAX = 1.0
SATURATION_OK = 0
SATURATION_UPPER = 2
SATURATION_LOWER = -2


class AllocationResult(NamedTuple):
    """One allocation (control_allocator_status content plus the motor commands)."""

    motors: tuple[float, ...]
    """Motor commands (normalised thrust) in [0, 1]."""
    allocated_torque: Vec3
    allocated_thrust: Vec3
    unallocated_torque: Vec3
    """Setpoint − allocated, normalised torque."""
    unallocated_thrust: Vec3
    torque_achieved: bool
    thrust_achieved: bool
    actuator_saturation: tuple[int, ...]
    """Per motor: 0 ok, +2 at maximum, −2 at minimum."""


def normalized_allocation(effectiveness: np.ndarray, normalize_rpy: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """PX4's allocation matrix: (N × 6 mix, 6-vector scale) such that u = mix · setpoint.

    The pseudo-inverse columns are divided by the scale: with ``normalize_rpy`` (multirotors) roll and pitch share
    max over the two of √(‖col‖² / (n_nonzero/2)) and yaw uses its largest element; each thrust axis, always, the
    mean |entry| of its non-zero entries (an axis without actuators takes the z scale). Entries below 1e-3 → 0.
    """
    mix = np.linalg.pinv(np.asarray(effectiveness, dtype=float))
    scale = np.ones(6)
    if normalize_rpy:
        rp_scale = []
        for axis in (0, 1):
            col = mix[:, axis]
            nonzero = int(np.count_nonzero(np.abs(col) > MIX_ZERO_THRESHOLD))
            rp_scale.append(math.sqrt(float(col @ col) / (nonzero / 2.0)) if nonzero > 0 else 1.0)
        scale[0] = scale[1] = max(rp_scale)
        scale[2] = float(mix[:, 2].max()) if mix.shape[0] > 0 else 1.0
    for axis in (5, 4, 3):
        magnitudes = np.abs(mix[:, axis])
        nonzero = int(np.count_nonzero(magnitudes > FLT_EPSILON))
        scale[axis] = float(magnitudes.sum()) / nonzero if nonzero > 0 else scale[5]
    if scale[0] > FLT_EPSILON:
        mix[:, 0:2] /= scale[0:2]
    if scale[2] > FLT_EPSILON:
        mix[:, 2] /= scale[2]
    if scale[3] > FLT_EPSILON:
        mix[:, 3:6] /= scale[3:6]
    mix[np.abs(mix) < MIX_ZERO_THRESHOLD] = 0.0
    return mix, scale


def _desaturation_gain(vec: tuple[float, ...], u: list[float], hi: float) -> float:
    k_min = 0.0
    k_max = 0.0
    for i, v in enumerate(vec):
        if -DESATURATION_MIN_ENTRY < v < DESATURATION_MIN_ENTRY:
            continue
        x = u[i]
        if x < ACTUATOR_MIN:
            k = (ACTUATOR_MIN - x) / v
        elif x > hi:
            k = (hi - x) / v
        else:
            continue
        if k < k_min:
            k_min = k
        if k > k_max:
            k_max = k
    return k_min + k_max


def desaturate(u: list[float], vec: tuple[float, ...], hi: float = ACTUATOR_MAX, reduce_only: bool = False,
               raise_only: bool = False) -> None:
    """Shift u in place along vec to bring saturated actuators back into [0, hi]: by the gain k_min + k_max
    over the violations (actuators with |vec_i| < 0.2 ignored), then by half of the gain recomputed after it.
    ``reduce_only`` skips a first gain below zero (along the thrust vector: never add thrust)."""
    gain = _desaturation_gain(vec, u, hi)
    if (reduce_only and gain < 0.0) or (raise_only and gain > 0.0):
        return
    for i, v in enumerate(vec):
        u[i] += gain * v
    gain = 0.5 * _desaturation_gain(vec, u, hi)
    for i, v in enumerate(vec):
        u[i] += gain * v


def thrust_has_priority(land: VehicleLandDetected | None) -> bool:
    """Whether airmode is off for this allocation: while a descent is demanded, and on the ground.

    ArduPilot's rule (``Copter::update_throttle_mix``: the throttle mix is at its minimum, attitude never
    raises the throttle, while landed and while a descent is demanded). A vehicle touching down tilted in wind
    tips onto its legs; with airmode, the torque that fights that rotation raised the collective thrust and
    lifted it off again, so that it hopped downwind for seconds before the land detector could settle.
    """
    return land is not None and (land.in_descend or land.ground_contact or land.maybe_landed or land.landed)


class ControlAllocator:
    """Pseudo-inverse allocation with PX4's sequential desaturation for a multirotor (actuators in [0, 1])."""

    __slots__ = ("_airmode", "_b", "_col_fx", "_col_fy", "_col_fz", "_col_p", "_col_r", "_col_y", "_mix",
                 "_n", "_scale")

    def __init__(self, effectiveness: np.ndarray, airmode: int = 0) -> None:
        self._airmode = 0
        self.set_airmode(airmode)
        self.set_effectiveness(effectiveness)

    @classmethod
    def from_params(cls, params: Mapping[str, object]) -> ControlAllocator:
        """Build from CA_ROTOR* geometry and MC_AIRMODE (missing → PX4 defaults)."""
        return cls(effectiveness_from_params(params), AllocatorParams.from_params(params).mc_airmode)

    def set_airmode(self, airmode: int) -> None:
        if airmode not in (0, 1, 2):
            raise ValueError(f"MC_AIRMODE must be 0, 1 or 2, got {airmode}")
        self._airmode = airmode

    def set_effectiveness(self, effectiveness: np.ndarray) -> None:
        """New 6 × N effectiveness (rows roll, pitch, yaw, Fx, Fy, Fz); weak rows are zeroed first."""
        b = np.array(effectiveness, dtype=float).reshape(6, -1)
        b[np.all(np.abs(b) <= WEAK_ROW_THRESHOLD, axis=1)] = 0.0
        mix, scale = normalized_allocation(b)
        self._n = b.shape[1]
        self._b = tuple(tuple(float(x) for x in row) for row in b)
        self._mix = mix
        self._scale = tuple(float(s) for s in scale)
        cols = tuple(tuple(float(x) for x in mix[:, j]) for j in range(6))
        self._col_r, self._col_p, self._col_y, self._col_fx, self._col_fy, self._col_fz = cols

    @property
    def num_motors(self) -> int:
        return self._n

    @property
    def mix(self) -> np.ndarray:
        """The normalised N × 6 allocation matrix (copy)."""
        return self._mix.copy()

    @property
    def scale(self) -> tuple[float, ...]:
        """Per-axis normalisation scale: allocated control = (B · u) ∘ scale."""
        return self._scale

    def allocate(self, torque: Vec3, thrust: Vec3, thrust_priority: bool = False) -> AllocationResult:
        """Motor commands for a normalised torque (roll, pitch, yaw) and body thrust (x, y, z; z < 0 is up).

        ``thrust_priority`` (see :func:`thrust_has_priority`): thrust has priority over attitude, as without
        airmode, so that torque demands never raise the collective thrust.
        """
        tr, tp, ty = torque
        fx, fy, fz = thrust
        cr, cp, cy = self._col_r, self._col_p, self._col_y
        cfx, cfy, cfz = self._col_fx, self._col_fy, self._col_fz
        u = [cr[i] * tr + cp[i] * tp + cfx[i] * fx + cfy[i] * fy + cfz[i] * fz for i in range(self._n)]
        airmode = 0 if thrust_priority else self._airmode
        if airmode == 2:
            desaturate(u, cfz)
            for i in range(self._n):
                u[i] += cy[i] * ty
            desaturate(u, cfz, raise_only=True)
            desaturate(u, cy, hi=ACTUATOR_MAX + MINIMUM_YAW_MARGIN * (ACTUATOR_MAX - ACTUATOR_MIN))
            desaturate(u, cfz, reduce_only=True)
        else:
            if airmode == 1:
                desaturate(u, cfz)
            else:
                desaturate(u, cfz, reduce_only=True)
                desaturate(u, cr)
                desaturate(u, cp)
            for i in range(self._n):
                u[i] += cy[i] * ty
            desaturate(u, cy, hi=ACTUATOR_MAX + MINIMUM_YAW_MARGIN * (ACTUATOR_MAX - ACTUATOR_MIN))
            desaturate(u, cfz, reduce_only=True)
        motors = tuple(ACTUATOR_MIN if x < ACTUATOR_MIN else ACTUATOR_MAX if x > ACTUATOR_MAX else x for x in u)
        return self._status(motors, (tr, tp, ty, fx, fy, fz))

    def _status(self, motors: tuple[float, ...], setpoint: tuple[float, ...]) -> AllocationResult:
        allocated = [sum(b * m for b, m in zip(row, motors, strict=True)) * s
                     for row, s in zip(self._b, self._scale, strict=True)]
        un = [sp - a for sp, a in zip(setpoint, allocated, strict=True)]
        torque_achieved = un[0] * un[0] + un[1] * un[1] + un[2] * un[2] < ACHIEVED_TOLERANCE
        thrust_achieved = un[3] * un[3] + un[4] * un[4] + un[5] * un[5] < ACHIEVED_TOLERANCE
        saturation = tuple(
            SATURATION_UPPER if m > ACTUATOR_MAX - FLT_EPSILON else SATURATION_LOWER if m < ACTUATOR_MIN + FLT_EPSILON
            else SATURATION_OK
            for m in motors
        )
        return AllocationResult(
            motors,
            (allocated[0], allocated[1], allocated[2]),
            (allocated[3], allocated[4], allocated[5]),
            (un[0], un[1], un[2]),
            (un[3], un[4], un[5]),
            torque_achieved,
            thrust_achieved,
            saturation,
        )
