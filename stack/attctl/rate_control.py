"""Multicopter body-rate PID: rate setpoint → normalised torque.

Follows PX4 ``src/lib/rate_control/rate_control.cpp`` (RateControl) together with the parts
of ``mc_rate_control/MulticopterRateControl.cpp`` that are pure computation: K-form gains, NaN rate
setpoints holding the current rate, NaN torques published as 0, the yaw-torque low-pass
(MC_YAW_TQ_CUTOFF) and the acro stick mapping.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from stack.mathlib.filters import AlphaFilter
from stack.mathlib.scalar import FLT_EPSILON, superexpo
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class RateControlParams(ParamSet):
    """The rate loop's gains in PX4's K-form (effective P/I/D = K × P/I/D), integrator limits and yaw torque
    cut-off (the catalogue's MC_*)."""

    mc_rollrate_p: float
    mc_rollrate_i: float
    mc_rollrate_d: float
    mc_rollrate_ff: float
    mc_rollrate_k: float
    mc_rr_int_lim: float
    mc_pitchrate_p: float
    mc_pitchrate_i: float
    mc_pitchrate_d: float
    mc_pitchrate_ff: float
    mc_pitchrate_k: float
    mc_pr_int_lim: float
    mc_yawrate_p: float
    mc_yawrate_i: float
    mc_yawrate_d: float
    mc_yawrate_ff: float
    mc_yawrate_k: float
    mc_yr_int_lim: float
    mc_yaw_tq_cutoff: float


class AcroParams(ParamSet):
    """Acro's full-stick rates and stick curves (the catalogue's MC_ACRO_*)."""

    mc_acro_r_max: float
    mc_acro_p_max: float
    mc_acro_y_max: float
    mc_acro_expo: float
    mc_acro_expo_y: float
    mc_acro_supexpo: float
    mc_acro_supexpoy: float


PARAMS: tuple[Param, ...] = RateControlParams.PARAMS
ACRO_PARAMS: tuple[Param, ...] = AcroParams.PARAMS

I_FACTOR_RATE = math.radians(400.0)
"""Rate error at which the integrator gain falls to zero (PX4 i_factor)."""


def integrator_factor(rate_error: float) -> float:
    """PX4's i_factor: 1 − (e / 400°/s)², floored at 0; ≈1 up to 100°/s, 0.75 at 200°/s."""
    f = rate_error / I_FACTOR_RATE
    return max(0.0, 1.0 - f * f)


def saturation_from_allocator(
    torque_achieved: bool, unallocated_torque: Vec3
) -> tuple[tuple[bool, bool, bool], tuple[bool, bool, bool]]:
    """``control_allocator_status`` → the (positive, negative) per-axis flags of ``RateControl.set_saturation_status``,
    as ``MulticopterRateControl::Run`` derives them: when the torque was not achieved, an axis whose unallocated
    torque exceeds FLT_EPSILON could not go further that way."""
    if torque_achieved:
        return (False, False, False), (False, False, False)
    ur, up, uy = unallocated_torque
    positive = (ur > FLT_EPSILON, up > FLT_EPSILON, uy > FLT_EPSILON)
    return positive, (ur < -FLT_EPSILON, up < -FLT_EPSILON, uy < -FLT_EPSILON)


class RateControl:
    """PX4's RateControl: torque = P·e + I − D·ω̇ + FF·ω_sp per axis, with a saturation-aware integrator."""

    __slots__ = ("_gain_d", "_gain_ff", "_gain_i", "_gain_p", "_int", "_lim_int", "_sat_neg", "_sat_pos")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._int = [0.0, 0.0, 0.0]
        self._sat_pos = [False, False, False]
        self._sat_neg = [False, False, False]
        self._gain_p: Vec3 = (0.0, 0.0, 0.0)
        self._gain_i: Vec3 = (0.0, 0.0, 0.0)
        self._gain_d: Vec3 = (0.0, 0.0, 0.0)
        self._gain_ff: Vec3 = (0.0, 0.0, 0.0)
        self._lim_int: Vec3 = (0.0, 0.0, 0.0)
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        """Apply the MC_*RATE_* and MC_*R_INT_LIM parameters in PX4's K-form (effective P/I/D = K × P/I/D)."""
        p = RateControlParams.from_params(params)
        k = (p.mc_rollrate_k, p.mc_pitchrate_k, p.mc_yawrate_k)
        self.set_gains(
            (k[0] * p.mc_rollrate_p, k[1] * p.mc_pitchrate_p, k[2] * p.mc_yawrate_p),
            (k[0] * p.mc_rollrate_i, k[1] * p.mc_pitchrate_i, k[2] * p.mc_yawrate_i),
            (k[0] * p.mc_rollrate_d, k[1] * p.mc_pitchrate_d, k[2] * p.mc_yawrate_d),
        )
        self.set_feed_forward_gain((p.mc_rollrate_ff, p.mc_pitchrate_ff, p.mc_yawrate_ff))
        self.set_integrator_limit((p.mc_rr_int_lim, p.mc_pr_int_lim, p.mc_yr_int_lim))

    def set_gains(self, p: Vec3, i: Vec3, d: Vec3) -> None:
        self._gain_p = tuple(p)
        self._gain_i = tuple(i)
        self._gain_d = tuple(d)

    def set_feed_forward_gain(self, ff: Vec3) -> None:
        self._gain_ff = tuple(ff)

    def set_integrator_limit(self, limit: Vec3) -> None:
        self._lim_int = tuple(limit)

    def set_saturation_status(self, positive: tuple[bool, bool, bool], negative: tuple[bool, bool, bool]) -> None:
        """Per-axis allocator saturation (roll, pitch, yaw): while an axis is saturated in a direction,
        its integrator may only move the other way."""
        self._sat_pos = [bool(v) for v in positive]
        self._sat_neg = [bool(v) for v in negative]

    def reset_integral(self) -> None:
        self._int = [0.0, 0.0, 0.0]

    @property
    def integral(self) -> Vec3:
        """Integrator states (rate_ctrl_status rollspeed/pitchspeed/yawspeed_integ), normalised torque."""
        return (self._int[0], self._int[1], self._int[2])

    def update(self, rate: Vec3, rate_sp: Vec3, angular_accel: Vec3, dt: float, landed: bool) -> Vec3:
        """Normalised torque for measured ``rate`` [rad/s], setpoint ``rate_sp`` (NaN axis = hold the
        current rate) and measured angular acceleration [rad/s²]. The integrator is frozen while landed.
        Non-finite torque components are returned as 0."""
        out = [0.0, 0.0, 0.0]
        gp, gi, gd, gff = self._gain_p, self._gain_i, self._gain_d, self._gain_ff
        integ = self._int
        for i in range(3):
            sp = rate_sp[i]
            if sp != sp:
                sp = rate[i]
            err = sp - rate[i]
            torque = gp[i] * err + integ[i] - gd[i] * angular_accel[i] + gff[i] * sp
            out[i] = torque if math.isfinite(torque) else 0.0
            if not landed:
                if self._sat_pos[i] and err > 0.0:
                    err = 0.0
                if self._sat_neg[i] and err < 0.0:
                    err = 0.0
                new = integ[i] + integrator_factor(err) * gi[i] * err * dt
                if math.isfinite(new):
                    lim = self._lim_int[i]
                    integ[i] = lim if new > lim else -lim if new < -lim else new
        return (out[0], out[1], out[2])


class YawTorqueLowPass:
    """First-order low-pass on the yaw torque (MC_YAW_TQ_CUTOFF, Hz; 0 = off), PX4's ``_output_lpf_yaw``:
    alpha = dt / (dt + 1/(2π·cutoff)) recomputed from each step's dt, state starting at 0."""

    __slots__ = ("_filter", "_tau")

    def __init__(self, cutoff_hz: float = 2.0) -> None:
        self._filter = AlphaFilter()
        self._filter.reset(0.0)
        self._tau = 0.0
        self.set_cutoff(cutoff_hz)

    def set_cutoff(self, cutoff_hz: float) -> None:
        self._tau = 1.0 / (2.0 * math.pi * cutoff_hz) if cutoff_hz > 0.0 else 0.0

    def reset(self, value: float = 0.0) -> None:
        self._filter.reset(value)

    def update(self, torque_z: float, dt: float) -> float:
        self._filter.set_time_constant(dt, self._tau)
        return self._filter.update(torque_z)


class AcroStickMapping:
    """PX4 acro mode: sticks → body-rate setpoint and thrust (MulticopterRateControl).

    Sticks follow manual_control_setpoint: each in [−1, 1], pitch +1 = stick forward = nose down,
    yaw + = clockwise, throttle −1 = minimum. Body rates (FRD): roll = roll stick, pitch = −pitch stick,
    yaw = yaw stick, each through superexpo and scaled by MC_ACRO_*_MAX.
    """

    __slots__ = ("_expo", "_expo_y", "_rate_max", "_supexpo", "_supexpo_y")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = AcroParams.from_params(params)
        self._rate_max = tuple(math.radians(r) for r in (p.mc_acro_r_max, p.mc_acro_p_max, p.mc_acro_y_max))
        self._expo = p.mc_acro_expo
        self._expo_y = p.mc_acro_expo_y
        self._supexpo = p.mc_acro_supexpo
        self._supexpo_y = p.mc_acro_supexpoy

    def rates(self, roll: float, pitch: float, yaw: float) -> Vec3:
        """Body-rate setpoint [rad/s] from the roll, pitch and yaw sticks."""
        m = self._rate_max
        return (
            superexpo(roll, self._expo, self._supexpo) * m[0],
            superexpo(-pitch, self._expo, self._supexpo) * m[1],
            superexpo(yaw, self._expo_y, self._supexpo_y) * m[2],
        )

    @staticmethod
    def thrust_body(throttle: float) -> Vec3:
        """Normalised body thrust from the throttle stick: collective (throttle + 1)/2 along −z."""
        return (0.0, 0.0, -(throttle + 1.0) * 0.5)
