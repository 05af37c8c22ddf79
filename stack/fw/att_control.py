"""Fixed-wing attitude and rate control: PX4 v1.13's fw_att_control as plain computation.

Follows the ECL controllers of ``src/modules/fw_att_control/`` (``ecl_roll_controller.cpp``,
``ecl_pitch_controller.cpp``, ``ecl_yaw_controller.cpp``, ``ecl_wheel_controller.cpp``, ``ecl_controller.cpp``)
and the computation in ``FixedwingAttitudeControl.cpp``:

- attitude: Euler-rate setpoints roll error / FW_R_TC, pitch error / FW_P_TC and the coordinated-turn yaw rate
  g·tanφ·cosθ / V, turned into body rates by the kinematic Jacobian and limited to FW_R_RMAX, FW_P_RMAX_POS/NEG
  and FW_Y_RMAX (FW_ACRO_*_MAX when the rates come from the sticks or from outside);
- rates, per axis: u = ω_sp·FF·s + (ω_sp − ω)·P·s² + I, the integrator adding (ω_sp − ω)·s²·I·dt within ±IMAX
  and never further into a saturated output, u within ±1. The airspeed scaling s = FW_AIRSPD_TRIM / V, V the
  calibrated airspeed within FW_AIRSPD_STALL … FW_AIRSPD_MAX, or FW_AIRSPD_TRIM (s = 1) without a valid one;
- the wheel controller, which steers the runway heading with a ground-speed scaling;
- the sticks of Manual (to surfaces), Stabilized (to angles) and Acro (to rates).

The integrators restart while landed (and stay at zero there), hold for steps longer than 20 ms
(FixedwingAttitudeControl.cpp), and hold while the measured airspeed is below half of FW_AIRSPD_MIN, as the ECL
controllers held them before they moved into PX4 (``control_bodyrate``: ``airspeed > 0.5f * airspeed_min``), so
that a plane rolling on the runway does not wind them up.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G, constrain, wrap_pi
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet, combine
from stack.params.param import Param


class FwAttControlParams(ParamSet):
    """The attitude and rate loops' time constants, rate limits and gains per axis, the wheel's, and the airspeeds
    their scaling takes (the catalogue's FW_*)."""

    fw_airspd_min: float
    fw_airspd_trim: float
    fw_airspd_max: float
    fw_airspd_stall: float
    fw_arsp_scale_en: bool
    fw_r_tc: float
    fw_p_tc: float
    fw_r_rmax: float
    fw_p_rmax_pos: float
    fw_p_rmax_neg: float
    fw_y_rmax: float
    fw_rr_p: float
    fw_rr_i: float
    fw_rr_ff: float
    fw_rr_imax: float
    fw_pr_p: float
    fw_pr_i: float
    fw_pr_ff: float
    fw_pr_imax: float
    fw_yr_p: float
    fw_yr_i: float
    fw_yr_ff: float
    fw_yr_imax: float
    fw_w_en: bool
    fw_wr_p: float
    fw_wr_i: float
    fw_wr_ff: float
    fw_wr_imax: float
    fw_w_rmax: float
    fw_acro_x_max: float
    fw_acro_y_max: float
    fw_acro_z_max: float


class StickMappingParams(ParamSet):
    """The manual modes' full-stick angles and scales, and Acro's full-stick rates (the catalogue's FW_*)."""

    fw_man_r_max: float
    fw_man_p_max: float
    fw_man_r_sc: float
    fw_man_p_sc: float
    fw_man_y_sc: float
    fw_acro_x_max: float
    fw_acro_y_max: float
    fw_acro_z_max: float


PARAMS: tuple[Param, ...] = combine(FwAttControlParams.PARAMS, StickMappingParams.PARAMS)

AIRSPEED_NUMERICAL_MIN = 0.5
"""Lowest airspeed [m/s] the controllers ever use (FixedwingAttitudeControl.cpp, against numerical trouble)."""
INTEGRATOR_LOCK_DT = 0.02
"""Steps longer than this [s] do not integrate (FixedwingAttitudeControl.cpp)."""
INTEGRATOR_AIRSPEED_FRACTION = 0.5
"""Below this fraction of FW_AIRSPD_MIN the integrators hold (the ECL controllers' ``0.5f * airspeed_min``)."""
COORDINATED_ROLL_MAX = math.radians(80.0)
"""The coordinated-turn rate takes the roll within ±80° (ecl_yaw_controller.cpp: tan φ stays finite)."""
INVERTED_ROLL = math.radians(90.0)
"""Beyond this roll the plane is inverted and the coordinated-turn rate keeps its last value (ecl_yaw_controller)."""
WHEEL_TIME_CONSTANT = 0.1
"""The wheel controller's heading time constant [s]: ECL_Controller's default, which v1.13 never changes."""
WHEEL_MIN_GROUNDSPEED = 1.0
"""Below this ground speed [m/s] the wheel controller does not integrate (ecl_wheel_controller.cpp)."""
WHEEL_MIN_RATE_LIMIT = 0.01
"""A wheel rate limit at or below this [rad/s] means no limit (ecl_wheel_controller.cpp)."""


class AttitudeTarget(NamedTuple):
    """What the attitude loop tracks: Euler angles [rad] (3-2-1, FRD → NED) and whether to steer on the ground."""

    roll: float
    pitch: float
    yaw: float
    wheel: bool = False


class ControlOutput(NamedTuple):
    rates_sp: Vec3
    """Body-rate setpoint [rad/s] (vehicle_rates_setpoint)."""
    torque: Vec3
    """Normalised torque in [−1, 1]: x aileron, y elevator, z rudder (or the steering wheel)."""


def controller_airspeed(calibrated_airspeed: float, trim: float) -> float:
    """The airspeed the controllers use: the calibrated airspeed (at least 0.5 m/s), or the trim airspeed when
    there is no valid one (NaN), as ``get_airspeed_and_update_scaling`` does."""
    if not math.isfinite(calibrated_airspeed):
        return trim
    return max(AIRSPEED_NUMERICAL_MIN, calibrated_airspeed)


def airspeed_scaler(airspeed: float, trim: float, stall: float, maximum: float, enabled: bool) -> float:
    """s = trim / airspeed, the airspeed held within [stall, maximum]; 1 when the scaling is off."""
    if not enabled:
        return 1.0
    return trim / constrain(constrain(airspeed, stall, maximum), 0.1, 1000.0)


def groundspeed_scaler(groundspeed: float, stall: float) -> float:
    """The wheel controller's scaling: stall / ground speed above the stall speed, else 1."""
    return stall / groundspeed if groundspeed > stall else 1.0


def coordinated_turn_rate(roll: float, pitch: float, roll_setpoint: float, airspeed: float,
                          airspeed_min: float) -> float | None:
    """The Euler yaw rate of a turn without sideslip, g·tanφ·cosθ / V (ecl_yaw_controller ``control_attitude``).

    φ is the roll within ±80° and within ±|roll setpoint|, V the airspeed at least ``airspeed_min``. None when
    inverted (|roll| ≥ 90°): the caller keeps its last rate."""
    if abs(roll) >= INVERTED_ROLL:
        return None
    limit = abs(roll_setpoint)
    bank = constrain(constrain(roll, -COORDINATED_ROLL_MAX, COORDINATED_ROLL_MAX), -limit, limit)
    speed = max(airspeed, airspeed_min)
    rate = math.tan(bank) * math.cos(pitch) * CONSTANTS_ONE_G / speed
    return rate if math.isfinite(rate) else 0.0


def euler_rates_to_body(roll: float, pitch: float, euler_rates: Vec3) -> Vec3:
    """Body rates (p, q, r) of Euler-angle rates (φ̇, θ̇, ψ̇), the Jacobian each ECL ``control_euler_rate`` applies:
    p = φ̇ − sinθ·ψ̇, q = cosφ·θ̇ + cosθ·sinφ·ψ̇, r = −sinφ·θ̇ + cosφ·cosθ·ψ̇."""
    roll_rate, pitch_rate, yaw_rate = euler_rates
    sr, cr = math.sin(roll), math.cos(roll)
    sp, cp = math.sin(pitch), math.cos(pitch)
    return (
        roll_rate - sp * yaw_rate,
        cr * pitch_rate + cp * sr * yaw_rate,
        -sr * pitch_rate + cr * cp * yaw_rate,
    )


class RateLoop:
    """One axis of the ECL body-rate controller (``control_bodyrate`` of the roll, pitch and yaw controllers)."""

    __slots__ = ("_last_output", "integrator", "integrator_max", "k_ff", "k_i", "k_p")

    def __init__(self, k_p: float = 0.0, k_i: float = 0.0, k_ff: float = 0.0, integrator_max: float = 0.0) -> None:
        self.k_p = k_p
        self.k_i = k_i
        self.k_ff = k_ff
        self.integrator_max = integrator_max
        self.integrator = 0.0
        self._last_output = 0.0

    def reset_integrator(self) -> None:
        self.integrator = 0.0

    def update(self, rate_sp: float, rate: float, scaler: float, dt: float, lock_integrator: bool) -> float:
        """Normalised output in [−1, 1] for a body-rate setpoint and measurement [rad/s] (finite inputs)."""
        error = rate_sp - rate
        if not lock_integrator and self.k_i > 0.0:
            step = error * dt * scaler * scaler
            # Anti-windup: while the unclamped output is beyond a limit, only move back towards the centre.
            if self._last_output < -1.0:
                step = max(step, 0.0)
            elif self._last_output > 1.0:
                step = min(step, 0.0)
            self.integrator = constrain(self.integrator + step * self.k_i, -self.integrator_max, self.integrator_max)
        self._last_output = rate_sp * self.k_ff * scaler + error * self.k_p * scaler * scaler + self.integrator
        return constrain(self._last_output, -1.0, 1.0)


class WheelLoop:
    """The ECL wheel controller: heading error → yaw rate (``control_attitude``) → steering (``control_bodyrate``)."""

    __slots__ = ("_last_output", "integrator", "integrator_max", "k_ff", "k_i", "k_p", "max_rate")

    def __init__(self) -> None:
        self.k_p = 0.0
        self.k_i = 0.0
        self.k_ff = 0.0
        self.integrator_max = 0.0
        self.max_rate = 0.0
        self.integrator = 0.0
        self._last_output = 0.0

    def reset_integrator(self) -> None:
        self.integrator = 0.0

    def rate_setpoint(self, yaw_setpoint: float, yaw: float) -> float:
        """Yaw-rate setpoint [rad/s]: the wrapped heading error over 0.1 s, within ±FW_W_RMAX."""
        rate = wrap_pi(yaw_setpoint - yaw) / WHEEL_TIME_CONSTANT
        if self.max_rate > WHEEL_MIN_RATE_LIMIT:
            rate = constrain(rate, -self.max_rate, self.max_rate)
        return rate

    def update(self, rate_sp: float, rate: float, groundspeed: float, stall: float, dt: float,
               lock_integrator: bool) -> float:
        """Steering in [−1, 1]: ω_sp·FF·g + g²·((ω_sp − ω)·P + I), g the ground-speed scaling. Without a finite
        ground speed the last output holds."""
        if not math.isfinite(groundspeed):
            return constrain(self._last_output, -1.0, 1.0)
        scaler = groundspeed_scaler(groundspeed, stall)
        error = rate_sp - rate
        if not lock_integrator and self.k_i > 0.0 and groundspeed > WHEEL_MIN_GROUNDSPEED:
            step = error * dt * scaler
            if self._last_output < -1.0:
                step = max(step, 0.0)
            elif self._last_output > 1.0:
                step = min(step, 0.0)
            self.integrator = constrain(self.integrator + step * self.k_i, -self.integrator_max, self.integrator_max)
        self._last_output = rate_sp * self.k_ff * scaler + scaler * scaler * (error * self.k_p + self.integrator)
        return constrain(self._last_output, -1.0, 1.0)


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


class FixedwingAttitudeController:
    """The attitude and rate loops of fw_att_control for roll, pitch and yaw, and the wheel controller.

    Non-finite inputs are refused (the call returns None and ``nonfinite_inputs`` counts them); a NaN airspeed
    means no valid airspeed."""

    __slots__ = ("_acro_max", "_p", "_pitch_rate_max_neg", "_pitch_rate_max_pos", "_roll_rate_max", "_wheel_enabled",
                 "_yaw_euler_rate", "_yaw_rate_max", "nonfinite_inputs", "pitch", "roll", "wheel", "yaw")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.roll = RateLoop()
        self.pitch = RateLoop()
        self.yaw = RateLoop()
        self.wheel = WheelLoop()
        self._yaw_euler_rate = 0.0
        self.nonfinite_inputs = 0
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = p = FwAttControlParams.from_params(params)
        self._roll_rate_max = math.radians(p.fw_r_rmax)
        self._pitch_rate_max_pos = math.radians(p.fw_p_rmax_pos)
        self._pitch_rate_max_neg = math.radians(p.fw_p_rmax_neg)
        self._yaw_rate_max = math.radians(p.fw_y_rmax)
        self._acro_max = tuple(math.radians(r) for r in (p.fw_acro_x_max, p.fw_acro_y_max, p.fw_acro_z_max))
        for loop, (k_p, k_i, k_ff, integrator_max) in (
            (self.roll, (p.fw_rr_p, p.fw_rr_i, p.fw_rr_ff, p.fw_rr_imax)),
            (self.pitch, (p.fw_pr_p, p.fw_pr_i, p.fw_pr_ff, p.fw_pr_imax)),
            (self.yaw, (p.fw_yr_p, p.fw_yr_i, p.fw_yr_ff, p.fw_yr_imax)),
            (self.wheel, (p.fw_wr_p, p.fw_wr_i, p.fw_wr_ff, p.fw_wr_imax)),
        ):
            loop.k_p, loop.k_i, loop.k_ff, loop.integrator_max = k_p, k_i, k_ff, integrator_max
        self._wheel_enabled = p.fw_w_en
        self.wheel.max_rate = math.radians(p.fw_w_rmax)

    def reset_integrals(self) -> None:
        for loop in (self.roll, self.pitch, self.yaw, self.wheel):
            loop.reset_integrator()

    @property
    def integrals(self) -> tuple[float, float, float, float]:
        """Integrator states (roll, pitch, yaw, wheel), normalised output."""
        return (self.roll.integrator, self.pitch.integrator, self.yaw.integrator, self.wheel.integrator)

    def airspeed(self, calibrated_airspeed: float) -> tuple[float, float]:
        """(The airspeed the loops use [m/s], the scaling s) for a measured calibrated airspeed (NaN: none)."""
        p = self._p
        v = controller_airspeed(calibrated_airspeed, p.fw_airspd_trim)
        return v, airspeed_scaler(v, p.fw_airspd_trim, p.fw_airspd_stall, p.fw_airspd_max, p.fw_arsp_scale_en)

    def _lock_integrator(self, calibrated_airspeed: float, dt: float, landed: bool) -> bool:
        """Whether this step holds the integrators; landed, they restart and stay at zero."""
        if landed:
            self.reset_integrals()
        slow_below = INTEGRATOR_AIRSPEED_FRACTION * self._p.fw_airspd_min
        slow = math.isfinite(calibrated_airspeed) and calibrated_airspeed < slow_below
        return landed or dt > INTEGRATOR_LOCK_DT or slow

    def attitude(self, q: Quat, rates: Vec3, target: AttitudeTarget, calibrated_airspeed: float, dt: float, *,
                 landed: bool, groundspeed: float = math.nan) -> ControlOutput | None:
        """Rates and torque that track ``target`` from attitude ``q`` and body rates ``rates`` [rad/s].

        With ``target.wheel`` and FW_W_EN the wheel controller steers the heading (the yaw loop restarts);
        otherwise the yaw loop flies the coordinated turn. ``groundspeed`` [m/s] scales the wheel controller."""
        if not (_finite(*q, *rates, target.roll, target.pitch, dt) and (math.isfinite(target.yaw) or not target.wheel)):
            self.nonfinite_inputs += 1
            return None
        roll, pitch, yaw = quat.to_euler(q)
        airspeed, scaler = self.airspeed(calibrated_airspeed)
        lock = self._lock_integrator(calibrated_airspeed, dt, landed)
        roll_rate = (target.roll - roll) / self._p.fw_r_tc
        pitch_rate = (target.pitch - pitch) / self._p.fw_p_tc
        wheel = target.wheel and self._wheel_enabled
        if wheel:
            self.yaw.reset_integrator()
        else:
            turn = coordinated_turn_rate(roll, pitch, target.roll, airspeed, self._p.fw_airspd_stall)
            if turn is not None:
                self._yaw_euler_rate = turn
            self.wheel.reset_integrator()
        body = euler_rates_to_body(roll, pitch, (roll_rate, pitch_rate, self._yaw_euler_rate))
        roll_sp = constrain(body[0], -self._roll_rate_max, self._roll_rate_max)
        pitch_sp = constrain(body[1], -self._pitch_rate_max_neg, self._pitch_rate_max_pos)
        torque_x = self.roll.update(roll_sp, rates[0], scaler, dt, lock)
        torque_y = self.pitch.update(pitch_sp, rates[1], scaler, dt, lock)
        if wheel:
            yaw_sp = self.wheel.rate_setpoint(target.yaw, yaw)
            torque_z = self.wheel.update(yaw_sp, rates[2], groundspeed, self._p.fw_airspd_stall, dt, lock)
        else:
            yaw_sp = constrain(body[2], -self._yaw_rate_max, self._yaw_rate_max)
            torque_z = self.yaw.update(yaw_sp, rates[2], scaler, dt, lock)
        return ControlOutput((roll_sp, pitch_sp, yaw_sp), (torque_x, torque_y, torque_z))

    def rates(self, rates: Vec3, rates_sp: Vec3, calibrated_airspeed: float, dt: float, *,
              landed: bool) -> ControlOutput | None:
        """Torque that tracks a body-rate setpoint [rad/s] (Acro, or rates from outside), limited by FW_ACRO_*_MAX."""
        if not _finite(*rates, *rates_sp, dt):
            self.nonfinite_inputs += 1
            return None
        _, scaler = self.airspeed(calibrated_airspeed)
        lock = self._lock_integrator(calibrated_airspeed, dt, landed)
        sp = tuple(constrain(v, -m, m) for v, m in zip(rates_sp, self._acro_max, strict=True))
        torque = tuple(
            loop.update(sp[i], rates[i], scaler, dt, lock) for i, loop in enumerate((self.roll, self.pitch, self.yaw))
        )
        return ControlOutput((sp[0], sp[1], sp[2]), (torque[0], torque[1], torque[2]))


class StickMapping:
    """The pilot's sticks in Manual, Stabilized and Acro (FixedwingAttitudeControl ``vehicle_manual_poll``).

    Sticks follow manual_control_setpoint: each in [−1, 1] (clamped here), roll + right, pitch + stick forward =
    nose down, yaw + nose right, throttle −1 = idle."""

    __slots__ = ("_acro_max", "_pitch_max", "_roll_max", "_scale")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = StickMappingParams.from_params(params)
        self._roll_max = math.radians(p.fw_man_r_max)
        self._pitch_max = math.radians(p.fw_man_p_max)
        self._scale = (p.fw_man_r_sc, p.fw_man_p_sc, p.fw_man_y_sc)
        self._acro_max = tuple(math.radians(r) for r in (p.fw_acro_x_max, p.fw_acro_y_max, p.fw_acro_z_max))

    def attitude(self, roll: float, pitch: float, yaw: float) -> AttitudeTarget:
        """Stabilized: roll = stick·FW_MAN_R_MAX, pitch = −stick·FW_MAN_P_MAX, heading ``yaw`` (not controlled)."""
        return AttitudeTarget(_stick(roll) * self._roll_max, -_stick(pitch) * self._pitch_max, yaw)

    def torque(self, roll: float, pitch: float, yaw: float) -> Vec3:
        """Manual: the sticks straight to aileron, elevator and rudder, scaled by FW_MAN_R/P/Y_SC."""
        sx, sy, sz = self._scale
        return (constrain(_stick(roll) * sx, -1.0, 1.0), constrain(-_stick(pitch) * sy, -1.0, 1.0),
                constrain(_stick(yaw) * sz, -1.0, 1.0))

    def rates(self, roll: float, pitch: float, yaw: float) -> Vec3:
        """Acro: body rates [rad/s] of FW_ACRO_X/Y/Z_MAX at full stick."""
        mx, my, mz = self._acro_max
        return (_stick(roll) * mx, -_stick(pitch) * my, _stick(yaw) * mz)

    @staticmethod
    def throttle(stick: float) -> float:
        """Throttle in [0, 1] from the stick in [−1, 1]."""
        return constrain((stick + 1.0) * 0.5, 0.0, 1.0)


def _stick(value: float) -> float:
    return constrain(value, -1.0, 1.0)
