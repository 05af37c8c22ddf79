"""Multicopter position and velocity controller (PX4 ``PositionControl``).

Follows ``src/modules/mc_pos_control/PositionControl/PositionControl.cpp``: a P position loop with
velocity feed-forward, a PID velocity loop whose D term acts on the (filtered) derivative of the
measured velocity, the conversion of the resulting acceleration into a normalised NED thrust vector
with tilt limit and vertical-first saturation, anti-windup, and finally an attitude setpoint from
the thrust direction and the yaw setpoint. NaN in a setpoint means "not controlled"; x and y must
be given or omitted together. Also holds ``failsafe_setpoint``, the setpoint PX4's
``MulticopterPositionControl`` falls back to when the requested setpoint cannot be executed.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G, FLT_EPSILON
from stack.mathlib.vector import NAN3, Vec3
from stack.params.binding import ParamSet
from stack.posctl.control_math import (
    add_if_not_nan,
    constrain_xy,
    limit_tilt,
    thrust_to_attitude,
)

HOVER_THRUST_MIN = 0.05
HOVER_THRUST_MAX = 0.9

_G = CONSTANTS_ONE_G
_isfinite = math.isfinite


class PositionControlParams(ParamSet):
    """Tunables of ``PositionControl``: the catalogue's MPC_* gains and limits (:mod:`stack.params.mpc`)."""

    mpc_xy_p: float
    mpc_z_p: float
    mpc_xy_vel_p_acc: float
    mpc_xy_vel_i_acc: float
    mpc_xy_vel_d_acc: float
    mpc_z_vel_p_acc: float
    mpc_z_vel_i_acc: float
    mpc_z_vel_d_acc: float
    mpc_xy_vel_max: float
    mpc_z_vel_max_up: float
    mpc_z_vel_max_dn: float
    mpc_tiltmax_air: float
    mpc_thr_min: float
    mpc_thr_max: float
    mpc_thr_hover: float
    mpc_thr_xy_marg: float
    mpc_acc_decouple: int
    """Tilt computed without the vertical acceleration setpoint (an enabled/disabled integer)."""


class LocalPositionSetpoint(NamedTuple):
    """What the controller actually executed (PX4 ``vehicle_local_position_setpoint``), NED."""

    position: Vec3
    velocity: Vec3
    acceleration: Vec3
    thrust: Vec3
    yaw: float
    yawspeed: float


class FailsafeSetpoint(NamedTuple):
    """A position/velocity/acceleration setpoint triple plus the name of the failsafe action."""

    position: Vec3
    velocity: Vec3
    acceleration: Vec3
    action: str


def failsafe_setpoint(velocity_estimate: Vec3, land_speed: float) -> FailsafeSetpoint:
    """Setpoint to fly when the requested one cannot be executed (PX4 ``generateFailsafeSetpoint``).

    In order of preference: stop horizontally (velocity 0) when the horizontal velocity estimate is
    valid, otherwise zero horizontal acceleration and descend at ``land_speed`` (MPC_LAND_SPEED);
    vertically hold velocity 0 (or the land speed) when the vertical velocity estimate is valid, otherwise
    command a_z = +0.3 m/s² ("blind descent", slightly below hover).
    """
    nan = math.nan
    vx = vy = vz = nan
    ax = ay = az = nan
    if _isfinite(velocity_estimate[0]) and _isfinite(velocity_estimate[1]):
        vx = vy = 0.0
        action = "stop and wait"
    else:
        ax = ay = 0.0
        vz = land_speed
        action = "blind land"
    if _isfinite(velocity_estimate[2]):
        if not _isfinite(vz):
            vz = 0.0
    else:
        vz = nan
        az = 0.3
        action = "blind descent"
    return FailsafeSetpoint(NAN3, (vx, vy, vz), (ax, ay, az), action)


class PositionControl:
    """PX4's cascaded P-position / PID-velocity controller producing a thrust vector and attitude.

    Per cycle: ``set_state``, ``set_setpoint``, ``update(dt)``; then read ``attitude_setpoint()``
    and ``local_position_setpoint()``. ``update`` returns False when the setpoint cannot be executed
    (an axis without any finite setpoint, x/y given unpaired, a missing state estimate for a
    controlled quantity, or a non-finite result); the caller then feeds ``failsafe_setpoint``.
    One departure from PX4: without a horizontal velocity estimate the frozen velocity integrator is
    still added to the acceleration, so a blind descent keeps leaning into the wind it had learned.
    """

    __slots__ = (
        "_acc_decouple",
        "_acc_sp",
        "_gain_pos_p",
        "_gain_vel_d",
        "_gain_vel_i",
        "_gain_vel_p",
        "_hover_thrust",
        "_lim_thr_max",
        "_lim_thr_min",
        "_lim_thr_xy_margin",
        "_lim_tilt",
        "_lim_vel_down",
        "_lim_vel_horizontal",
        "_lim_vel_up",
        "_pos",
        "_pos_sp",
        "_thr_sp",
        "_vel",
        "_vel_dot",
        "_vel_int",
        "_vel_sp",
        "_yaw",
        "_yaw_sp",
        "_yawspeed_sp",
    )

    def __init__(self, params: PositionControlParams | None = None) -> None:
        self._pos = NAN3
        self._vel = NAN3
        self._vel_dot = NAN3
        self._yaw = 0.0
        self._pos_sp = NAN3
        self._vel_sp = NAN3
        self._acc_sp = NAN3
        self._thr_sp = NAN3
        self._yaw_sp = math.nan
        self._yawspeed_sp = math.nan
        self._vel_int: list[float] = [0.0, 0.0, 0.0]
        self.set_params(params or PositionControlParams())

    # -- configuration ---------------------------------------------------------------------------

    def set_params(self, params: PositionControlParams) -> None:
        """Apply a full parameter set (gains, limits, hover thrust, decoupling)."""
        self.set_gains(
            (params.mpc_xy_p, params.mpc_xy_p, params.mpc_z_p),
            (params.mpc_xy_vel_p_acc, params.mpc_xy_vel_p_acc, params.mpc_z_vel_p_acc),
            (params.mpc_xy_vel_i_acc, params.mpc_xy_vel_i_acc, params.mpc_z_vel_i_acc),
            (params.mpc_xy_vel_d_acc, params.mpc_xy_vel_d_acc, params.mpc_z_vel_d_acc),
        )
        self.set_limits(
            vel_horizontal=params.mpc_xy_vel_max,
            vel_up=params.mpc_z_vel_max_up,
            vel_down=params.mpc_z_vel_max_dn,
            thrust_min=params.mpc_thr_min,
            thrust_max=params.mpc_thr_max,
            thrust_xy_margin=params.mpc_thr_xy_marg,
            tilt_max=math.radians(params.mpc_tiltmax_air),
        )
        self.set_hover_thrust(params.mpc_thr_hover)
        self._acc_decouple = params.mpc_acc_decouple

    def set_gains(self, pos_p: Vec3, vel_p: Vec3, vel_i: Vec3, vel_d: Vec3) -> None:
        """Per-axis (x, y, z) gains: position P [1/s], velocity P [1/s], I [1/s²], D [-]."""
        self._gain_pos_p = tuple(pos_p)
        self._gain_vel_p = tuple(vel_p)
        self._gain_vel_i = tuple(vel_i)
        self._gain_vel_d = tuple(vel_d)

    def set_limits(
        self,
        *,
        vel_horizontal: float | None = None,
        vel_up: float | None = None,
        vel_down: float | None = None,
        thrust_min: float | None = None,
        thrust_max: float | None = None,
        thrust_xy_margin: float | None = None,
        tilt_max: float | None = None,
    ) -> None:
        """Change any of the limits; arguments left at None keep their value.

        Speeds in m/s (vel_up and vel_down both positive), thrusts normalised, tilt_max in rad.
        The minimum thrust is kept ≥ 1e-3 so the thrust vector always defines an attitude.
        """
        if vel_horizontal is not None:
            self._lim_vel_horizontal = vel_horizontal
        if vel_up is not None:
            self._lim_vel_up = vel_up
        if vel_down is not None:
            self._lim_vel_down = vel_down
        if thrust_min is not None:
            self._lim_thr_min = max(thrust_min, 1e-3)
        if thrust_max is not None:
            self._lim_thr_max = thrust_max
        if thrust_xy_margin is not None:
            self._lim_thr_xy_margin = thrust_xy_margin
        if tilt_max is not None:
            self._lim_tilt = tilt_max

    def set_hover_thrust(self, hover_thrust: float) -> None:
        """Set the hover thrust directly, clamped to [0.05, 0.9]; the integrator is left untouched. NaN is
        dropped."""
        if hover_thrust == hover_thrust:
            self._hover_thrust = min(max(hover_thrust, HOVER_THRUST_MIN), HOVER_THRUST_MAX)

    def update_hover_thrust(self, hover_thrust_new: float) -> None:
        """Switch to a new hover thrust estimate without a thrust step.

        With T = (a − g)·Th/g, keeping T while Th → Th' needs a' = (a − g)·Th/Th' + g, so a' − a is
        added to the vertical integrator (which feeds a directly).
        """
        if hover_thrust_new > FLT_EPSILON:
            az = self._acc_sp[2]
            if _isfinite(az):
                self._vel_int[2] += (az - _G) * self._hover_thrust / hover_thrust_new + _G - az
            self.set_hover_thrust(hover_thrust_new)

    @property
    def hover_thrust(self) -> float:
        return self._hover_thrust

    @property
    def velocity_integral(self) -> Vec3:
        """Integrator state of the velocity loop [m/s²]."""
        return (self._vel_int[0], self._vel_int[1], self._vel_int[2])

    def reset_integral(self) -> None:
        self._vel_int[0] = self._vel_int[1] = self._vel_int[2] = 0.0

    def resume_integral(self, vel_int: Vec3) -> bool:
        """Take over the integrator state of an earlier instance (what holds the vehicle against a steady
        wind); refused, changing nothing, unless it is three finite values of at most g each."""
        if not isinstance(vel_int, list | tuple) or len(vel_int) != 3:
            return False
        if not all(isinstance(v, float | int) and abs(v) <= _G for v in vel_int):
            return False
        self._vel_int[:] = [float(v) for v in vel_int]
        return True

    # -- per-cycle inputs ------------------------------------------------------------------------

    def set_state(self, pos: Vec3, vel: Vec3, vel_dot: Vec3, yaw: float) -> None:
        """Current estimate: position [m], velocity [m/s], filtered velocity derivative [m/s²], yaw (a
        non-finite yaw keeps the last finite one, the heading a missing yaw setpoint holds)."""
        self._pos = pos
        self._vel = vel
        self._vel_dot = vel_dot
        if _isfinite(yaw):
            self._yaw = yaw

    def set_setpoint(self, pos: Vec3, vel: Vec3, acc: Vec3, yaw: float, yawspeed: float) -> None:
        """Trajectory setpoint (NaN = not controlled; velocity and acceleration act as feed-forward)."""
        self._pos_sp = pos
        self._vel_sp = vel
        self._acc_sp = acc
        self._yaw_sp = yaw
        self._yawspeed_sp = yawspeed

    # -- control ---------------------------------------------------------------------------------

    def update(self, dt: float) -> bool:
        """Run one control cycle; True if the output thrust and attitude setpoints are valid."""
        if not _isfinite(self._yawspeed_sp):
            self._yawspeed_sp = 0.0
        if not _isfinite(self._yaw_sp):
            self._yaw_sp = self._yaw
        if not self.input_valid():
            return False
        self._position_control()
        self._velocity_control(dt)
        a = self._acc_sp
        t = self._thr_sp
        return (
            _isfinite(a[0])
            and _isfinite(a[1])
            and _isfinite(a[2])
            and _isfinite(t[0])
            and _isfinite(t[1])
            and _isfinite(t[2])
        )

    def input_valid(self) -> bool:
        """Every axis has a finite setpoint, x/y come in pairs, controlled states have estimates."""
        p, v, a = self._pos_sp, self._vel_sp, self._acc_sp
        for i in (0, 1, 2):
            if not (_isfinite(p[i]) or _isfinite(v[i]) or _isfinite(a[i])):
                return False
        if (
            _isfinite(p[0]) != _isfinite(p[1])
            or _isfinite(v[0]) != _isfinite(v[1])
            or _isfinite(a[0]) != _isfinite(a[1])
        ):
            return False
        for i in (0, 1, 2):
            if _isfinite(p[i]) and not _isfinite(self._pos[i]):
                return False
            if _isfinite(v[i]) and not (_isfinite(self._vel[i]) and _isfinite(self._vel_dot[i])):
                return False
        return True

    def _position_control(self) -> None:
        kx, ky, kz = self._gain_pos_p
        psx, psy, psz = self._pos_sp
        px, py, pz = self._pos
        # NaN in a setpoint or a state makes its P term NaN, which add_if_not_nan ignores.
        vpx = (psx - px) * kx
        vpy = (psy - py) * ky
        vpz = (psz - pz) * kz
        vsx = add_if_not_nan(self._vel_sp[0], vpx)
        vsy = add_if_not_nan(self._vel_sp[1], vpy)
        vsz = add_if_not_nan(self._vel_sp[2], vpz)
        if not _isfinite(vpx):
            vpx = 0.0
        if not _isfinite(vpy):
            vpy = 0.0
        vsx, vsy = constrain_xy((vpx, vpy), (vsx - vpx, vsy - vpy), self._lim_vel_horizontal)
        if vsz < -self._lim_vel_up:
            vsz = -self._lim_vel_up
        elif vsz > self._lim_vel_down:
            vsz = self._lim_vel_down
        self._vel_sp = (vsx, vsy, vsz)

    def _velocity_control(self, dt: float) -> None:
        vel_int = self._vel_int
        if vel_int[2] > _G:
            vel_int[2] = _G
        elif vel_int[2] < -_G:
            vel_int[2] = -_G
        kpx, kpy, kpz = self._gain_vel_p
        kdx, kdy, kdz = self._gain_vel_d
        ex = self._vel_sp[0] - self._vel[0]
        ey = self._vel_sp[1] - self._vel[1]
        ez = self._vel_sp[2] - self._vel[2]
        vdx, vdy, vdz = self._vel_dot
        if _isfinite(self._vel[0]) and _isfinite(self._vel[1]):
            asx = add_if_not_nan(self._acc_sp[0], ex * kpx + vel_int[0] - vdx * kdx)
            asy = add_if_not_nan(self._acc_sp[1], ey * kpy + vel_int[1] - vdy * kdy)
        else:
            # Flying blind horizontally, the frozen integrator is the last measure of the wind:
            # keep leaning into it rather than fly level and drift downwind.
            asx = self._acc_sp[0] + vel_int[0]
            asy = self._acc_sp[1] + vel_int[1]
        asz = add_if_not_nan(self._acc_sp[2], ez * kpz + vel_int[2] - vdz * kdz)
        self._acc_sp = (asx, asy, asz)

        tx, ty, tz = self._acceleration_control(asx, asy, asz)

        thr_min = self._lim_thr_min
        thr_max = self._lim_thr_max
        # Vertical anti-windup: no integration further into a saturated thrust limit.
        if (tz >= -thr_min and ez >= 0.0) or (tz <= -thr_max and ez <= 0.0):
            ez = 0.0

        # Saturation: vertical first, but keep up to MPC_THR_XY_MARG for the horizontal part.
        txy = math.hypot(tx, ty)
        thr_max_sq = thr_max * thr_max
        allocated_xy = min(txy, self._lim_thr_xy_margin)
        tz_max = math.sqrt(max(thr_max_sq - allocated_xy * allocated_xy, 0.0))
        if tz < -tz_max:
            tz = -tz_max
        txy_max_sq = thr_max_sq - tz * tz
        txy_max = math.sqrt(txy_max_sq) if txy_max_sq > 0.0 else 0.0
        if txy > txy_max:
            scale = txy_max / txy
            tx *= scale
            ty *= scale
        self._thr_sp = (tx, ty, tz)

        # Horizontal tracking anti-reset windup (Rundqwist 1990), active only when saturated.
        acc_per_thrust = _G / self._hover_thrust
        ax_prod = tx * acc_per_thrust
        ay_prod = ty * acc_per_thrust
        if asx * asx + asy * asy > ax_prod * ax_prod + ay_prod * ay_prod:
            arw_gain = 2.0 / kpx
            ex -= arw_gain * (asx - ax_prod)
            ey -= arw_gain * (asy - ay_prod)

        # An error or a dt that is not finite (a NaN setpoint axis, a bad clock) leaves the integrator as it is.
        kix, kiy, kiz = self._gain_vel_i
        for i, increment in enumerate((ex * kix * dt, ey * kiy * dt, ez * kiz * dt)):
            if _isfinite(increment):
                vel_int[i] += increment

    def _acceleration_control(self, ax: float, ay: float, az: float) -> Vec3:
        if not (_isfinite(ax) and _isfinite(ay) and _isfinite(az)):
            return NAN3
        # With MPC_ACC_DECOUPLE the tilt assumes a_z = 0, so climbing does not change the tilt.
        up = _G if self._acc_decouple else _G - az
        n = math.sqrt(ax * ax + ay * ay + up * up)
        body_z = (0.0, 0.0, 1.0) if n < FLT_EPSILON else (-ax / n, -ay / n, up / n)
        bx, by, bz = limit_tilt(body_z, (0.0, 0.0, 1.0), self._lim_tilt)
        hover = self._hover_thrust
        thrust_ned_z = az * (hover / _G) - hover
        collective = thrust_ned_z / bz
        if collective > -self._lim_thr_min:
            collective = -self._lim_thr_min
        return (bx * collective, by * collective, bz * collective)

    # -- outputs ---------------------------------------------------------------------------------

    def attitude_setpoint(self) -> tuple[Quat, Vec3, float]:
        """(q_d, thrust_body, yaw_sp_move_rate) for ``vehicle_attitude_setpoint``."""
        q_d, thrust_body = thrust_to_attitude(self._thr_sp, self._yaw_sp)
        return q_d, thrust_body, self._yawspeed_sp

    def local_position_setpoint(self) -> LocalPositionSetpoint:
        """Executed setpoints for telemetry: input position, velocity after the position loop,
        acceleration after the velocity loop, normalised NED thrust, yaw and yaw rate."""
        return LocalPositionSetpoint(
            self._pos_sp, self._vel_sp, self._acc_sp, self._thr_sp, self._yaw_sp, self._yawspeed_sp
        )

    @property
    def thrust_setpoint(self) -> Vec3:
        """Normalised NED thrust vector of the last update."""
        return self._thr_sp

