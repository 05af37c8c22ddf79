"""ArduPilot's attitude input shaping, as a selectable front end to PX4's attitude controller.

Follows ``libraries/AP_Math/control.cpp`` (sqrt_controller, inv_sqrt_controller) and
``libraries/AC_AttitudeControl/AC_AttitudeControl.cpp`` (input_shaping_angle / _ang_vel,
euler_accel_limit, Euler-rate ↔ body-rate conversion, ang_vel_limit, the input_* entry points and the
feed-forward part of attitude_controller_run_quat). ArduPilot keeps three attitudes: *desired* (what the
caller asks for), *target* (a rate- and acceleration-limited trajectory toward desired) and *measured*.
``AttitudeInputShaper`` owns the target: each input_* call integrates it by the target angular velocity,
computes a new target angular velocity, and returns the target attitude plus the target angular
velocity rotated into the current body frame as feed-forward. In our stack the target quaternion goes
to ``AttitudeControl`` (target vs measured) and ``combine_with_feedforward`` adds the feed-forward to its
rate setpoint. ``AttitudeSetpointShaping`` decides whether the shaper is used at all (MC_INPUT_SHAPING)
and when it engages.

Angles are in rad and rates in rad/s; the ArduPilot parameters keep their own units (cdeg, deg).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.attctl.attitude_control import AttitudeControl
from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import is_negative, is_positive, is_zero, wrap_pi
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class InputShapingParams(ParamSet):
    """ArduPilot's ATC_* shaping and the acro rate time constants (the catalogue's)."""

    atc_input_tc: float
    atc_accel_r_max: float
    atc_accel_p_max: float
    atc_accel_y_max: float
    atc_rate_ff_enab: int
    atc_slew_yaw: float
    atc_rate_r_max: float
    atc_rate_p_max: float
    atc_rate_y_max: float
    acro_rp_rate_tc: float
    acro_y_rate_tc: float


PARAMS: tuple[Param, ...] = InputShapingParams.PARAMS

THRUST_ERROR_ANGLE = math.radians(30.0)
"""ArduPilot ``AC_ATTITUDE_THRUST_ERROR_ANGLE``: beyond it the feed-forward fades out, gone at twice it."""


def sqrt_controller(error: float, p: float, second_ord_lim: float, dt: float) -> float:
    """ArduPilot's sqrt_controller: P near zero error, constant-deceleration square root beyond
    ``second_ord_lim / p²``, never more than ``|error| / dt`` (no overshoot in one step)."""
    if is_negative(second_ord_lim) or is_zero(second_ord_lim):
        rate = error * p
    elif is_zero(p):
        if is_positive(error):
            rate = math.sqrt(2.0 * second_ord_lim * error)
        elif is_negative(error):
            rate = -math.sqrt(-2.0 * second_ord_lim * error)
        else:
            rate = 0.0
    else:
        linear_dist = second_ord_lim / (p * p)
        if error > linear_dist:
            rate = math.sqrt(2.0 * second_ord_lim * (error - 0.5 * linear_dist))
        elif error < -linear_dist:
            rate = -math.sqrt(2.0 * second_ord_lim * (-error - 0.5 * linear_dist))
        else:
            rate = error * p
    if is_positive(dt):
        max_rate = abs(error) / dt
        rate = max(-max_rate, min(max_rate, rate))
    return rate


def inv_sqrt_controller(output: float, p: float, d_max: float) -> float:
    """Inverse of ``sqrt_controller`` (without the dt clamp): the error that produces ``output``.

    As upstream, the pure square-root case (p = 0) returns an unsigned distance.
    """
    if is_positive(d_max) and is_zero(p):
        return output * output / (2.0 * d_max)
    if not is_positive(d_max):
        return 0.0 if is_zero(p) else output / p
    if abs(output) < d_max / p:
        return output / p
    stopping = 0.5 * d_max / (p * p) + output * output / (2.0 * d_max)
    return stopping if is_positive(output) else -stopping


def input_shaping_ang_vel(target_rate: float, desired_rate: float, accel_max: float, dt: float,
                          input_tc: float = 0.0) -> float:
    """Move ``target_rate`` toward ``desired_rate``: first-order lag ``input_tc`` (if > 0), then at most
    ``accel_max · dt`` change (if accel_max > 0)."""
    if input_tc > 0.0:
        step = sqrt_controller(desired_rate - target_rate, 1.0 / max(input_tc, 0.01), 0.0, dt)
        desired_rate = target_rate + step * dt
    if accel_max > 0.0:
        delta = accel_max * dt
        return max(target_rate - delta, min(target_rate + delta, desired_rate))
    return desired_rate


def input_shaping_angle(error: float, input_tc: float, accel_max: float, target_rate: float, dt: float,
                        desired_rate: float = 0.0, max_rate: float = 0.0) -> float:
    """New target rate for an angle error: sqrt_controller with gain 1/input_tc plus ``desired_rate``,
    limited to ±max_rate (if > 0), then acceleration-limited against the current ``target_rate``."""
    desired_rate += sqrt_controller(error, 1.0 / max(input_tc, 0.01), accel_max, dt)
    if max_rate > 0.0:
        desired_rate = max(-max_rate, min(max_rate, desired_rate))
    return input_shaping_ang_vel(target_rate, desired_rate, accel_max, dt)


def euler_accel_limit(euler: Vec3, accel: Vec3) -> Vec3:
    """Body-axis acceleration limits (roll, pitch, yaw) → Euler-rate acceleration limits at attitude
    ``euler`` (roll, pitch, yaw) such that no body axis exceeds its own limit. Any limit ≤ 0 (off)
    returns the input unchanged."""
    if accel[0] <= 0.0 or accel[1] <= 0.0 or accel[2] <= 0.0:
        return accel
    sin_phi = min(max(abs(math.sin(euler[0])), 0.1), 1.0)
    cos_phi = min(max(abs(math.cos(euler[0])), 0.1), 1.0)
    sin_theta = min(max(abs(math.sin(euler[1])), 0.1), 1.0)
    cos_theta = min(max(abs(math.cos(euler[1])), 0.1), 1.0)
    return (
        accel[0],
        min(accel[1] / cos_phi, accel[2] / sin_phi),
        min(accel[0] / sin_theta, accel[1] / (sin_phi * cos_theta), accel[2] / (cos_phi * cos_theta)),
    )


def euler_rate_to_ang_vel(euler: Vec3, euler_rate: Vec3) -> Vec3:
    """3-2-1 Euler-angle rates → body angular velocity (p, q, r) at attitude ``euler``."""
    sp, cp = math.sin(euler[0]), math.cos(euler[0])
    st, ct = math.sin(euler[1]), math.cos(euler[1])
    rr, pr, yr = euler_rate
    return (rr - st * yr, cp * pr + sp * ct * yr, -sp * pr + cp * ct * yr)


def ang_vel_to_euler_rate(euler: Vec3, ang_vel: Vec3) -> Vec3 | None:
    """Body angular velocity → 3-2-1 Euler-angle rates; None within FLT_EPSILON of cos(pitch) = 0 (±90°, where
    the Euler angles are singular), as ArduPilot's AC_AttitudeControl::ang_vel_to_euler_rate refuses."""
    sp, cp = math.sin(euler[0]), math.cos(euler[0])
    st, ct = math.sin(euler[1]), math.cos(euler[1])
    if is_zero(ct):
        return None
    p, q, r = ang_vel
    tt = st / ct
    return (p + sp * tt * q + cp * tt * r, cp * q - sp * r, (sp * q + cp * r) / ct)


def ang_vel_limit(ang_vel: Vec3, roll_max: float, pitch_max: float, yaw_max: float) -> Vec3:
    """ArduPilot's ang_vel_limit: with both roll and pitch limits set, scale (p/roll_max, q/pitch_max)
    to at most unit length (keeps the tilt-rate direction); otherwise clamp per axis. 0 = no limit."""
    p, q, r = ang_vel
    if roll_max == 0.0 or pitch_max == 0.0:
        if roll_max != 0.0:
            p = max(-roll_max, min(roll_max, p))
        if pitch_max != 0.0:
            q = max(-pitch_max, min(pitch_max, q))
    else:
        length = math.hypot(p / roll_max, q / pitch_max)
        if length > 1.0:
            p /= length
            q /= length
    if yaw_max != 0.0:
        r = max(-yaw_max, min(yaw_max, r))
    return (p, q, r)


class ShapedAttitude(NamedTuple):
    """One shaper output. ``rate_ff`` is the target angular velocity in the current body frame with the
    roll/pitch components already faded by ``feedforward_scale`` (1 up to 30° thrust error, 0 beyond 60°);
    its yaw component is unfaded, because the fade applies to the whole yaw demand (see
    ``combine_with_feedforward``)."""

    q_target: Quat
    rate_ff: Vec3
    feedforward_scale: float
    thrust_error_angle: float


def combine_with_feedforward(rate_correction: Vec3, shaped: ShapedAttitude, gyro: Vec3) -> Vec3:
    """Add the shaper's feed-forward to an attitude controller's rate setpoint, as ArduPilot does.

    Roll/pitch: correction + faded feed-forward. Yaw: (correction + feed-forward) blended toward the
    measured yaw rate as the thrust error grows, so a large tilt error is fixed first with yaw left alone.
    """
    s = shaped.feedforward_scale
    ff = shaped.rate_ff
    yaw = rate_correction[2] + ff[2]
    return (rate_correction[0] + ff[0], rate_correction[1] + ff[1], gyro[2] * (1.0 - s) + yaw * s)


class AttitudeInputShaper:
    """ArduPilot's target-attitude shaper (AC_AttitudeControl input_* functions), stateful.

    Call ``reset(q_body)`` when it is engaged, then one input_* method per control step with the
    measured attitude and dt; each returns a ``ShapedAttitude``.
    """

    __slots__ = ("_accel_max", "_euler_rate", "_ff_enabled", "_input_tc", "_q_target", "_rate_max",
                 "_rate_rp_tc", "_rate_y_tc", "_slew_yaw_max", "_target_rate")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._q_target: Quat = quat.IDENTITY
        self._target_rate: Vec3 = (0.0, 0.0, 0.0)
        self._euler_rate: Vec3 = (0.0, 0.0, 0.0)
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        """Apply the ATC_* / ACRO_*_RATE_TC parameters (missing → ArduPilot Copter default)."""
        p = InputShapingParams.from_params(params)
        self._input_tc = p.atc_input_tc
        self._accel_max = tuple(
            math.radians(a * 0.01) for a in (p.atc_accel_r_max, p.atc_accel_p_max, p.atc_accel_y_max)
        )
        self._rate_max = tuple(math.radians(r) for r in (p.atc_rate_r_max, p.atc_rate_p_max, p.atc_rate_y_max))
        self._ff_enabled = p.atc_rate_ff_enab != 0
        slew = math.radians(p.atc_slew_yaw * 0.01)
        self._slew_yaw_max = min(slew, self._rate_max[2]) if self._rate_max[2] > 0.0 else slew
        self._rate_rp_tc = p.acro_rp_rate_tc
        self._rate_y_tc = p.acro_y_rate_tc

    @property
    def q_target(self) -> Quat:
        return self._q_target

    @property
    def target_rate(self) -> Vec3:
        """Target angular velocity [rad/s] in the target frame."""
        return self._target_rate

    def reset(self, q_body: Quat) -> None:
        """Start from the measured attitude, at rest (ArduPilot reset_target_and_rate)."""
        self._q_target = quat.normalized(q_body)
        self._target_rate = (0.0, 0.0, 0.0)
        self._euler_rate = (0.0, 0.0, 0.0)

    def adapt_to_reset(self, delta_q: Quat) -> None:
        """Shift the target by an estimator reset (``q_new = delta_q ⊗ q_old``)."""
        self._q_target = quat.normalized(quat.mul(delta_q, self._q_target))

    def input_euler_angle_roll_pitch_yaw(self, roll: float, pitch: float, yaw: float, slew_yaw: bool,
                                         q_body: Quat, dt: float) -> ShapedAttitude:
        """Follow absolute Euler angles [rad]; with ``slew_yaw`` the yaw rate is held to the ATC_SLEW_YAW limit."""
        self._advance_target(dt)
        euler = quat.to_euler(self._q_target)
        if self._ff_enabled:
            a = euler_accel_limit(euler, self._accel_max)
            tc = self._input_tc
            er = self._euler_rate
            rr = input_shaping_angle(wrap_pi(roll - euler[0]), tc, a[0], er[0], dt)
            pr = input_shaping_angle(wrap_pi(pitch - euler[1]), tc, a[1], er[1], dt)
            yr = input_shaping_angle(wrap_pi(yaw - euler[2]), tc, a[2], er[2], dt)
            if slew_yaw:
                yr = max(-self._slew_yaw_max, min(self._slew_yaw_max, yr))
            self._set_target_rate_from_euler(euler, (rr, pr, yr))
        else:
            if slew_yaw:
                step = self._slew_yaw_max * dt
                yaw = wrap_pi(euler[2] + max(-step, min(step, wrap_pi(yaw - euler[2]))))
            self._q_target = quat.from_euler(roll, pitch, yaw)
            self._zero_rates()
        return self._output(q_body)

    def input_quaternion(self, q_desired: Quat, q_body: Quat, dt: float,
                         desired_rate: Vec3 = (0.0, 0.0, 0.0)) -> ShapedAttitude:
        """Follow a desired attitude, shaping each axis of the rotation vector of target⁻¹ ⊗ desired.

        ``desired_rate`` is the desired attitude's own body rate [rad/s], fed forward. ArduPilot adds it
        as expressed in NED; here it is rotated into the target frame, which matches for small errors.
        """
        self._advance_target(dt)
        rm = self._rate_max
        desired_rate = ang_vel_limit(desired_rate, rm[0], rm[1], rm[2])
        if self._ff_enabled:
            q_err = quat.mul(quat.conj(self._q_target), q_desired)
            error = quat.to_rotation_vector(q_err)
            wd = quat.rotate(q_err, desired_rate)
            tc = self._input_tc
            am = self._accel_max
            tr = self._target_rate
            self._target_rate = tuple(
                input_shaping_angle(wrap_pi(error[i]), tc, am[i], tr[i], dt, wd[i], rm[i]) for i in range(3)
            )
        else:
            self._q_target = quat.normalized(q_desired)
            self._target_rate = desired_rate
        self._update_euler_rate()
        return self._output(q_body)

    def input_rate_bf_roll_pitch_yaw(self, rates: Vec3, q_body: Quat, dt: float) -> ShapedAttitude:
        """Stabilised acro: body-rate commands [rad/s] shaped by ACRO_*_RATE_TC and the acceleration limits;
        the target attitude integrates them, so releasing the sticks holds the attitude reached."""
        self._advance_target(dt)
        if self._ff_enabled:
            tr = self._target_rate
            am = self._accel_max
            self._target_rate = (
                input_shaping_ang_vel(tr[0], rates[0], am[0], dt, self._rate_rp_tc),
                input_shaping_ang_vel(tr[1], rates[1], am[1], dt, self._rate_rp_tc),
                input_shaping_ang_vel(tr[2], rates[2], am[2], dt, self._rate_y_tc),
            )
            self._update_euler_rate()
        else:
            step = quat.from_rotation_vector((rates[0] * dt, rates[1] * dt, rates[2] * dt))
            self._q_target = quat.normalized(quat.mul(self._q_target, step))
            self._zero_rates()
        return self._output(q_body)

    def _advance_target(self, dt: float) -> None:
        r = self._target_rate
        self._q_target = quat.integrate(self._q_target, r, dt)

    def _set_target_rate_from_euler(self, euler: Vec3, euler_rate: Vec3) -> None:
        rm = self._rate_max
        body = ang_vel_limit(euler_rate_to_ang_vel(euler, euler_rate), rm[0], rm[1], rm[2])
        self._target_rate = body
        limited = ang_vel_to_euler_rate(euler, body)
        self._euler_rate = limited if limited is not None else euler_rate

    def _update_euler_rate(self) -> None:
        converted = ang_vel_to_euler_rate(quat.to_euler(self._q_target), self._target_rate)
        if converted is not None:
            self._euler_rate = converted

    def _zero_rates(self) -> None:
        self._target_rate = (0.0, 0.0, 0.0)
        self._euler_rate = (0.0, 0.0, 0.0)

    def _output(self, q_body: Quat) -> ShapedAttitude:
        q_t = self._q_target
        # Target rate seen from the current body frame.
        ff = quat.rotate(quat.mul(quat.conj(q_body), q_t), self._target_rate)
        # Angle between the measured and the target thrust axes.
        zb = quat.dcm_z(q_body)
        zt = quat.dcm_z(q_t)
        cos_err = zb[0] * zt[0] + zb[1] * zt[1] + zb[2] * zt[2]
        err = math.acos(max(-1.0, min(1.0, cos_err)))
        if err > 2.0 * THRUST_ERROR_ANGLE:
            s = 0.0
        elif err > THRUST_ERROR_ANGLE:
            s = 1.0 - (err - THRUST_ERROR_ANGLE) / THRUST_ERROR_ANGLE
        else:
            s = 1.0
        return ShapedAttitude(q_t, (ff[0] * s, ff[1] * s, ff[2]), s, err)


class AttitudeSetpointShaping:
    """The attitude setpoint's way into ``AttitudeControl``, with or without the shaper (MC_INPUT_SHAPING).

    Without it the setpoint and its yaw feed-forward go to the controller as PX4 does. With it the shaper's
    target goes instead and its rates are fed forward; the shaper engages, from the measured attitude at rest,
    on the first attitude-controlled step after it was released. Call ``release()`` on every step that does not
    control the attitude; a parameter change releases it too.
    """

    __slots__ = ("_engaged", "enabled", "shaper")

    def __init__(self, params: Mapping[str, object] | None = None, enabled: bool = False) -> None:
        self.shaper = AttitudeInputShaper(params)
        self.enabled = enabled
        self._engaged = False

    def set_params(self, params: Mapping[str, object], enabled: bool) -> None:
        """The shaper's ATC_* parameters and MC_INPUT_SHAPING."""
        self.shaper.set_params(params)
        self.enabled = enabled
        self._engaged = False

    @property
    def engaged(self) -> bool:
        return self._engaged

    def release(self) -> None:
        self._engaged = False

    def adapt_to_reset(self, delta_q: Quat) -> None:
        """Shift the shaper's target by an estimator reset (``q_new = delta_q ⊗ q_old``)."""
        self.shaper.adapt_to_reset(delta_q)

    def rates(self, control: AttitudeControl, q_d: Quat, yaw_sp_move_rate: float, q: Quat, gyro: Vec3,
              dt: float) -> Vec3:
        """Body-rate setpoint [rad/s] toward ``q_d`` for the measured attitude ``q`` and body rates ``gyro``."""
        if not self.enabled:
            control.set_attitude_setpoint(q_d, yaw_sp_move_rate)
            return control.update(q)
        if not self._engaged:
            self.shaper.reset(q)
            self._engaged = True
        shaped = self.shaper.input_quaternion(q_d, q, dt)
        control.set_attitude_setpoint(shaped.q_target, math.nan)
        return combine_with_feedforward(control.update(q), shaped, gyro)
