"""Attitude setpoints from pilot commands: PX4 Stabilized mode, rattitude, and RotorS's
roll / pitch / yaw-rate / thrust command.

* ``StabilizedAttitudeSetpoint`` follows ``MulticopterAttitudeControl::generate_attitude_setpoint`` and
  ``throttle_curve`` in PX4's ``mc_att_control_main.cpp`` (yaw setpoint integrated from the stick as in
  v1.13), with the manual throttle slews of its ``Run()``.
* ``rattitude_uses_rate_control`` is the rattitude switch of the older mc_att_control (MC_RATT_TH in
  ``mc_att_control_main.cpp``, removed from PX4 in 2021).
* ``rotors_attitude_setpoint`` turns a RotorS ``roll_pitch_yawrate_thrust_controller`` command
  (``rotors_control/src/library/roll_pitch_yawrate_thrust_controller.cpp``), in the stack's frames, into an
  attitude setpoint, so PX4's attitude loop can fly the RotorS mode.

Sticks follow manual_control_setpoint: each in [−1, 1], pitch +1 = stick forward = nose down,
yaw + = clockwise, throttle −1 = minimum.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.mathlib import quaternion as quat
from stack.mathlib.filters import AlphaFilter, SlewRate
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import interpolate, wrap_pi
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class StabilizedParams(ParamSet):
    """The sticks' tilt, yaw rate and thrust mapping (the catalogue's), and what arming and air mode change in it."""

    mpc_man_tilt_max: float
    mc_man_tilt_tau: float
    mpc_man_y_max: float
    mpc_manthr_min: float
    mpc_thr_hover: float
    mpc_thr_max: float
    mpc_thr_curve: int
    com_spoolup_time: float
    mc_airmode: int
    mc_ratt_th: float


PARAMS: tuple[Param, ...] = StabilizedParams.PARAMS

THROTTLE_MIN_SLEW = 0.05
"""Slew rate [1/s] of the minimum manual thrust and of the hover thrust (PX4)."""
THROTTLE_MAX_SLEW = 0.5
"""Slew rate [1/s] of the maximum manual thrust once spooled up (PX4)."""
ARMING_GESTURE_THROTTLE = -0.9


class AttitudeSetpoint(NamedTuple):
    """vehicle_attitude_setpoint content: q_d (body FRD → NED), yaw feed-forward [rad/s about world z],
    normalised body thrust (multicopter: (0, 0, −collective))."""

    q_d: Quat
    yaw_sp_move_rate: float
    thrust_body: Vec3


class StabilizedAttitudeSetpoint:
    """PX4 Stabilized mode: roll/pitch sticks → tilt, yaw stick → yaw rate with a held heading,
    throttle stick → collective thrust through MPC_THR_CURVE and the spool-up limits."""

    __slots__ = ("_airmode", "_hover", "_hover_estimate", "_hover_param", "_man_thr_min", "_pitch_filter",
                 "_roll_filter", "_spoolup_time", "_thr_curve", "_thr_max", "_thr_max_limit", "_thr_min_limit",
                 "_tilt_max", "_tilt_tau", "_yaw_max", "_yaw_sp")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._roll_filter = AlphaFilter()
        self._pitch_filter = AlphaFilter()
        self._thr_min_limit = SlewRate(THROTTLE_MIN_SLEW, 0.0)
        self._thr_max_limit = SlewRate(THROTTLE_MAX_SLEW, 0.0)
        self._hover = SlewRate(THROTTLE_MIN_SLEW, 0.0)
        self._hover_estimate = math.nan
        self._yaw_sp = math.nan
        self.set_params(params or {})
        self.reset()

    def set_params(self, params: Mapping[str, object]) -> None:
        p = StabilizedParams.from_params(params)
        self._tilt_max = math.radians(p.mpc_man_tilt_max)
        self._tilt_tau = p.mc_man_tilt_tau
        self._yaw_max = math.radians(p.mpc_man_y_max)
        self._man_thr_min = p.mpc_manthr_min
        self._hover_param = p.mpc_thr_hover
        self._thr_max = p.mpc_thr_max
        self._thr_curve = p.mpc_thr_curve
        self._spoolup_time = p.com_spoolup_time
        self._airmode = p.mc_airmode
        if not math.isfinite(self._hover_estimate):
            self._hover.set_forced_value(self._hover_param)

    def reset(self) -> None:
        """On entering Stabilized: clear the stick filters; the next setpoint takes the current heading."""
        self._roll_filter.reset(0.0)
        self._pitch_filter.reset(0.0)
        self._yaw_sp = math.nan

    def set_hover_thrust_estimate(self, hover_thrust: float) -> None:
        """Hover thrust from the estimator (clamped to [0.05, 0.9]); NaN slews back to MPC_THR_HOVER."""
        self._hover_estimate = min(max(hover_thrust, 0.05), 0.9) if math.isfinite(hover_thrust) else self._hover_param

    def update_throttle_limits(self, dt: float, landed: bool, armed: bool, now_us: int, armed_time_us: int) -> None:
        """Advance the thrust slews (PX4 does this after publishing): the minimum slews to 0 on the ground
        and to MPC_MANTHR_MIN in flight; the maximum stays 0 until COM_SPOOLUP_TIME after arming, then
        ramps to 1 at 50 %/s; the hover thrust follows its estimate."""
        self._thr_min_limit.update(0.0 if landed else self._man_thr_min, dt)
        if armed and now_us - armed_time_us > self._spoolup_time * 1e6:
            self._thr_max_limit.update(1.0, dt)
        else:
            self._thr_max_limit.set_forced_value(0.0)
        if math.isfinite(self._hover_estimate):
            self._hover.update(self._hover_estimate, dt)

    def throttle_curve(self, throttle: float) -> float:
        """Collective thrust for a throttle stick in [−1, 1] (MPC_THR_CURVE), capped by the spool-up limit."""
        lo = self._thr_min_limit.state
        if self._thr_curve == 1:
            thrust = interpolate(throttle, -1.0, 1.0, lo, self._thr_max)
        elif throttle < 0.0:
            thrust = interpolate(throttle, -1.0, 0.0, lo, self._hover.state)
        else:
            thrust = interpolate(throttle, 0.0, 1.0, self._hover.state, self._thr_max)
        return min(thrust, self._thr_max_limit.state)

    def adapt_to_heading_reset(self, delta_yaw: float) -> None:
        """Shift the held heading by an estimator yaw reset."""
        if math.isfinite(self._yaw_sp):
            self._yaw_sp = wrap_pi(self._yaw_sp + delta_yaw)

    def generate(self, q: Quat, roll: float, pitch: float, yaw: float, throttle: float, dt: float,
                 reset_yaw: bool = False) -> AttitudeSetpoint:
        """Attitude setpoint for the current attitude ``q`` and the sticks.

        The tilt vector (roll, −pitch)·MPC_MAN_TILT_MAX (each filtered with MC_MAN_TILT_TAU, norm-limited)
        is an axis-angle tilt; the heading integrates yaw·MPC_MAN_Y_MAX and holds when the stick is
        centred. The heading restarts from the current yaw on ``reset_yaw``, after ``reset()``, and during
        the arming gesture (throttle < −0.9, unless MC_AIRMODE is 2).
        """
        yaw_rate = yaw * self._yaw_max
        if reset_yaw or (throttle < ARMING_GESTURE_THROTTLE and self._airmode != 2) or not math.isfinite(self._yaw_sp):
            self._yaw_sp = quat.yaw(q)
        else:
            self._yaw_sp = wrap_pi(self._yaw_sp + yaw_rate * dt)
        self._roll_filter.set_time_constant(dt, self._tilt_tau)
        self._pitch_filter.set_time_constant(dt, self._tilt_tau)
        vx = self._roll_filter.update(roll * self._tilt_max)
        vy = -self._pitch_filter.update(pitch * self._tilt_max)
        tilt = math.hypot(vx, vy)
        if tilt > self._tilt_max:
            vx *= self._tilt_max / tilt
            vy *= self._tilt_max / tilt
        q_tilt = quat.from_rotation_vector((vx, vy, 0.0))
        half = 0.5 * self._yaw_sp
        q_d = quat.mul((math.cos(half), 0.0, 0.0, math.sin(half)), q_tilt)
        return AttitudeSetpoint(q_d, yaw_rate, (0.0, 0.0, -self.throttle_curve(throttle)))


def rattitude_uses_rate_control(roll: float, pitch: float, threshold: float = 0.8) -> bool:
    """Rattitude mode: True when |roll| or |pitch| stick exceeds MC_RATT_TH, i.e. the attitude controller
    is bypassed and the sticks command body rates (use ``AcroStickMapping``); otherwise the sticks
    command angles as in Stabilized."""
    return abs(roll) > threshold or abs(pitch) > threshold


def rotors_attitude_setpoint(heading: float, command: RollPitchYawrateThrust, max_thrust: float) -> AttitudeSetpoint:
    """Attitude setpoint for PX4's attitude loop from a RotorS command in the stack's frames.

    RotorS' controller holds R_des = Rz(ψ)·Rx(φ)·Ry(θ) in ENU/FLU; conjugated into NED/FRD with the stack's pitch
    (+ nose up) that is R_des = Rz(``heading``)·Rx(roll)·Ry(pitch), and the commanded yaw rate (clockwise +, about
    NED down) is the yaw feed-forward. The thrust [N] is normalised by ``max_thrust`` [N], the collective thrust at
    full command, and clipped to [0, 1].
    """
    half_yaw = 0.5 * heading
    heading = (math.cos(half_yaw), 0.0, 0.0, math.sin(half_yaw))
    q_d = quat.mul(
        quat.mul(heading, quat.from_axis_angle((1.0, 0.0, 0.0), command.roll)),
        quat.from_axis_angle((0.0, 1.0, 0.0), command.pitch),
    )
    collective = min(max(command.thrust / max_thrust, 0.0), 1.0) if max_thrust > 0.0 else 0.0
    return AttitudeSetpoint(q_d, command.yaw_rate, (0.0, 0.0, -collective))
