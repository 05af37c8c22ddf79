"""Jerk-limited velocity profiles (PX4 ``VelocitySmoothing``) and their 3-axis synchronisation.

Follows ``src/lib/motion_planning/VelocitySmoothing.cpp``. Each call to ``update_durations`` plans,
from the current (acceleration, velocity), the minimum-time move to a target velocity in three
phases: T1 at constant jerk ±j_max, T2 at constant (saturated) acceleration, T3 at the opposite
jerk back to zero acceleration. ``update_traj`` then integrates that piecewise-cubic profile
exactly. Replanning every cycle from the integrated state keeps jerk, acceleration and velocity
within their limits. ``VelocitySmoothing3D`` makes the three axes end together: straight-line
motion is planned once along the line (so it stays exactly on it), anything else per axis with
the shorter axes stretched to the longest duration as PX4's ``timeSynchronization`` does.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3

_COLLINEAR_TOL = 1e-6


class TrajectoryPoint(NamedTuple):
    """A kinematically consistent NED setpoint: position, velocity, acceleration, jerk."""

    position: Vec3
    velocity: Vec3
    acceleration: Vec3
    jerk: Vec3


def _sign(x: float) -> int:
    return 1 if x > 0.0 else -1 if x < 0.0 else 0


class VelocitySmoothing:
    """One axis of a jerk-limited trajectory (PX4 ``VelocitySmoothing``).

    Limits: ``max_jerk`` [m/s³], ``max_accel`` [m/s²], ``max_vel`` [m/s] (callers pass the PX4
    parameters, e.g. MPC_JERK_AUTO, MPC_ACC_HOR, MPC_XY_VEL_MAX). The state is public read-only:
    ``jerk``, ``accel``, ``vel``, ``pos``; the planned phase durations are ``t1``, ``t2``, ``t3``.
    """

    __slots__ = (
        "_a0",
        "_direction",
        "_local_time",
        "_plan_jerk",
        "_v0",
        "_vel_sp",
        "_x0",
        "accel",
        "jerk",
        "max_accel",
        "max_jerk",
        "max_vel",
        "pos",
        "t1",
        "t2",
        "t3",
        "vel",
    )

    def __init__(
        self,
        accel: float = 0.0,
        vel: float = 0.0,
        pos: float = 0.0,
        *,
        max_jerk: float = 4.0,
        max_accel: float = 3.0,
        max_vel: float = 12.0,
    ) -> None:
        self.max_jerk = max_jerk
        self.max_accel = max_accel
        self.max_vel = max_vel
        self._vel_sp = 0.0
        self._direction = 0
        self._plan_jerk = 0.0
        self._local_time = 0.0
        self.t1 = self.t2 = self.t3 = 0.0
        self.reset(accel, vel, pos)

    def reset(self, accel: float, vel: float, pos: float) -> None:
        """Restart from the given state with zero jerk and no planned motion."""
        self.jerk = 0.0
        self.accel = accel
        self.vel = vel
        self.pos = pos
        self._a0 = accel
        self._v0 = vel
        self._x0 = pos
        self._local_time = 0.0
        self.t1 = self.t2 = self.t3 = 0.0
        self._direction = 0
        self._plan_jerk = 0.0

    def set_current_position(self, pos: float) -> None:
        """Overwrite the position (state and plan start); takes full effect at the next plan."""
        self.pos = self._x0 = pos

    def set_current_velocity(self, vel: float) -> None:
        """Overwrite the velocity (state and plan start); takes full effect at the next plan."""
        self.vel = self._v0 = vel

    def set_current_acceleration(self, accel: float) -> None:
        """Overwrite the acceleration (state and plan start); takes full effect at the next plan."""
        self.accel = self._a0 = accel

    @property
    def total_time(self) -> float:
        """Duration T1 + T2 + T3 of the planned profile [s]."""
        return self.t1 + self.t2 + self.t3

    @property
    def first_phase_jerk(self) -> float:
        """Signed jerk of the T1 phase of the current plan [m/s³] (T3 uses its opposite)."""
        return self._plan_jerk

    @property
    def velocity_target(self) -> float:
        """Target velocity of the current plan (after the ±max_vel clamp)."""
        return self._vel_sp

    # -- planning --------------------------------------------------------------------------------

    def update_durations(self, vel_target: float) -> None:
        """Plan the minimum-time profile from the current state to ``vel_target``."""
        self._start_plan(vel_target)
        jerk = self._plan_jerk = self._direction * self.max_jerk
        if abs(jerk) > FLT_EPSILON:
            dv = self._vel_sp - self.vel
            self.t1 = self._t1_free(self.accel, dv, jerk)
            self.t3 = max(self.accel / jerk + self.t1, 0.0)
            self.t2 = self._t2_free(self.t1, self.t3, self.accel, dv, jerk)
        else:
            self.t1 = self.t2 = self.t3 = 0.0

    def update_durations_given_total_time(self, total_time: float) -> None:
        """Stretch the plan made by ``update_durations`` so that it takes ``total_time`` seconds.

        The three-phase shape cannot always be stretched (e.g. a large initial acceleration and a
        small velocity change); when the stretched plan would miss the target, the minimum-time
        plan is kept (PX4 keeps the broken plan, which can overshoot the velocity limit).
        """
        jerk = self._direction * self.max_jerk
        if abs(jerk) <= FLT_EPSILON:
            return
        a0 = self.accel
        dv = self._vel_sp - self.vel
        t1 = self._t1_given_total(total_time, a0, dv, jerk)
        t3 = max(a0 / jerk + t1, 0.0)
        t2 = max(total_time - t1 - t3, 0.0)
        a_end = a0 + jerk * (t1 - t3)
        dv_planned = a0 * (t1 + t2 + t3) + jerk * (0.5 * t1 * t1 + t1 * (t2 + t3) - 0.5 * t3 * t3)
        tolerance = 1e-6 * (1.0 + abs(dv))
        if abs(a_end) <= tolerance and abs(dv_planned - dv) <= tolerance:
            self.t1, self.t2, self.t3 = t1, t2, t3
            self._plan_jerk = jerk

    def follow_profile(self, t1: float, t2: float, t3: float, jerk: float, vel_target: float) -> None:
        """Replace the current plan by given phase durations and first-phase jerk (signed).

        Used to give several axes proportional copies of one profile; the caller is responsible
        for the limits.
        """
        self.t1, self.t2, self.t3 = t1, t2, t3
        self._plan_jerk = jerk
        self._direction = _sign(jerk)
        self._vel_sp = vel_target

    def _start_plan(self, vel_target: float) -> None:
        self._vel_sp = min(max(vel_target, -self.max_vel), self.max_vel)
        self._local_time = 0.0
        self._a0 = self.accel
        self._v0 = self.vel
        self._x0 = self.pos
        # Direction of the first jerk phase: compare the target with the velocity reached by
        # bringing the current acceleration to zero as fast as possible.
        a = self.accel
        vel_zero_acc = self.vel
        if abs(a) > FLT_EPSILON:
            j_zero = -_sign(a) * self.max_jerk
            t_zero = -a / j_zero
            vel_zero_acc = self.vel + a * t_zero + 0.5 * j_zero * t_zero * t_zero
        direction = _sign(self._vel_sp - vel_zero_acc)
        self._direction = direction if direction != 0 else _sign(a)

    def _saturate_t1(self, a0: float, jerk: float, t1: float) -> float:
        a_end = a0 + jerk * t1
        if a_end > self.max_accel:
            return (self.max_accel - a0) / jerk
        if a_end < -self.max_accel:
            return (-self.max_accel - a0) / jerk
        return t1

    def _t1_free(self, a0: float, dv: float, jerk: float) -> float:
        # Without a constant-acceleration phase: a0·T1 + ½j·T1² + (a0 + j·T1)·T3 − ½j·T3² = dv with
        # T3 = a0/j + T1, a quadratic in T1. With the direction taken from the zero-acceleration
        # velocity its discriminant is never negative, so a negative value is rounding at the
        # "just brake the acceleration" boundary and is treated as 0 (PX4 gives up there with
        # T1 = 0, which plans a short constant-acceleration overshoot of the target).
        delta = max(2.0 * a0 * a0 + 4.0 * jerk * dv, 0.0)
        sqrt_delta = math.sqrt(delta)
        t1_plus = (-a0 + 0.5 * sqrt_delta) / jerk
        t1_minus = (-a0 - 0.5 * sqrt_delta) / jerk
        t1 = 0.0
        if t1_plus >= 0.0 and a0 / jerk + t1_plus >= 0.0:
            t1 = t1_plus
        elif t1_minus >= 0.0 and a0 / jerk + t1_minus >= 0.0:
            t1 = t1_minus
        return max(self._saturate_t1(a0, jerk, t1), 0.0)

    def _t1_given_total(self, total: float, a0: float, dv: float, jerk: float) -> float:
        # Same velocity balance with T2 = total − T1 − T3: −j·T1² + (j·total − a0)·T1 + … = 0.
        qa = -jerk
        qb = jerk * total - a0
        delta = total * total * jerk * jerk + 2.0 * total * a0 * jerk - a0 * a0 - 4.0 * jerk * dv
        if delta < 0.0:
            return 0.0
        sqrt_delta = math.sqrt(delta)
        inv_den = 1.0 / (2.0 * qa)
        t1_plus = max((-qb + sqrt_delta) * inv_den, 0.0)
        t1_minus = max((-qb - sqrt_delta) * inv_den, 0.0)
        t3_plus = a0 / jerk + t1_plus
        t3_minus = a0 / jerk + t1_minus
        t1 = 0.0
        if t3_plus >= 0.0 and t1_plus + t3_plus <= total:
            t1 = t1_plus
        elif t3_minus >= 0.0 and t1_minus + t3_minus <= total:
            t1 = t1_minus
        return self._saturate_t1(a0, jerk, t1)

    @staticmethod
    def _t2_free(t1: float, t3: float, a0: float, dv: float, jerk: float) -> float:
        den = a0 + jerk * t1
        if abs(den) <= FLT_EPSILON:
            return 0.0
        t2 = (-0.5 * t1 * t1 * jerk - t1 * t3 * jerk - t1 * a0 + 0.5 * t3 * t3 * jerk - t3 * a0 + dv) / den
        return max(t2, 0.0)

    # -- integration -----------------------------------------------------------------------------

    def update_traj(self, dt: float, time_stretch: float = 1.0) -> None:
        """Advance along the current plan by dt·time_stretch seconds (exact cubic integration)."""
        self._local_time += dt * time_stretch
        remaining = self._local_time
        j = self._plan_jerk

        t = min(remaining, self.t1)
        a = self._a0 + j * t
        v = self._v0 + (self._a0 + 0.5 * j * t) * t
        x = self._x0 + (self._v0 + (0.5 * self._a0 + j * t / 6.0) * t) * t
        jerk = j
        remaining -= t

        if remaining > 0.0:
            t = min(remaining, self.t2)
            x += (v + 0.5 * a * t) * t
            v += a * t
            jerk = 0.0
            remaining -= t

        if remaining > 0.0:
            t = min(remaining, self.t3)
            x += (v + (0.5 * a - j * t / 6.0) * t) * t
            v += (a - 0.5 * j * t) * t
            a -= j * t
            jerk = -j
            remaining -= t

        if remaining > 0.0:
            x += v * remaining
            a = 0.0
            jerk = 0.0

        self.jerk = jerk
        self.accel = a
        self.vel = v
        self.pos = x


def synchronize_durations(axes: tuple[VelocitySmoothing, ...]) -> None:
    """Stretch every axis to the longest planned duration (PX4 ``timeSynchronization``)."""
    longest = 0.0
    longest_index = 0
    for i, axis in enumerate(axes):
        total = axis.total_time
        if total > longest:
            longest = total
            longest_index = i
    if longest > FLT_EPSILON:
        for i, axis in enumerate(axes):
            if i != longest_index and axis.total_time < longest:
                axis.update_durations_given_total_time(longest)


def _common_direction(accel: Vec3, vel: Vec3, target: Vec3) -> Vec3 | None:
    """Unit vector that acceleration, velocity and target are all parallel to, else None."""
    for ref in (target, vel, accel):
        n = math.sqrt(ref[0] * ref[0] + ref[1] * ref[1] + ref[2] * ref[2])
        if n > _COLLINEAR_TOL:
            u = (ref[0] / n, ref[1] / n, ref[2] / n)
            break
    else:
        return None
    for w in (accel, vel, target):
        cx = w[1] * u[2] - w[2] * u[1]
        cy = w[2] * u[0] - w[0] * u[2]
        cz = w[0] * u[1] - w[1] * u[0]
        if cx * cx + cy * cy + cz * cz > _COLLINEAR_TOL * _COLLINEAR_TOL:
            return None
    return u


class VelocitySmoothing3D:
    """Three time-synchronised ``VelocitySmoothing`` axes (x, y, z NED).

    ``update_durations`` plans all axes to end together. When the current acceleration, velocity
    and target are collinear (straight-line motion), the move is planned once along that line,
    with each axis's jerk, acceleration and velocity limit projected onto it, and every axis gets
    the proportional copy of that profile, so the path stays exactly on the line. Otherwise each
    axis is planned on its own and the shorter ones are stretched to the longest duration (PX4
    ``timeSynchronization``).
    """

    __slots__ = ("_line", "axes")

    def __init__(
        self,
        *,
        max_jerk: Vec3 = (4.0, 4.0, 4.0),
        max_accel: Vec3 = (3.0, 3.0, 4.0),
        max_vel: Vec3 = (12.0, 12.0, 3.0),
    ) -> None:
        self.axes = tuple(
            VelocitySmoothing(max_jerk=j, max_accel=a, max_vel=v)
            for j, a, v in zip(max_jerk, max_accel, max_vel, strict=True)
        )
        self._line = VelocitySmoothing()

    def reset(self, accel: Vec3, vel: Vec3, pos: Vec3) -> None:
        for i, axis in enumerate(self.axes):
            axis.reset(accel[i], vel[i], pos[i])

    def set_limits(
        self, *, max_jerk: Vec3 | None = None, max_accel: Vec3 | None = None, max_vel: Vec3 | None = None
    ) -> None:
        """Per-axis limits; None leaves a group unchanged."""
        for i, axis in enumerate(self.axes):
            if max_jerk is not None:
                axis.max_jerk = max_jerk[i]
            if max_accel is not None:
                axis.max_accel = max_accel[i]
            if max_vel is not None:
                axis.max_vel = max_vel[i]

    def update_durations(self, vel_target: Vec3) -> None:
        ax, ay, az = self.axes
        accel = (ax.accel, ay.accel, az.accel)
        vel = (ax.vel, ay.vel, az.vel)
        ax.update_durations(vel_target[0])
        ay.update_durations(vel_target[1])
        az.update_durations(vel_target[2])
        direction = _common_direction(accel, vel, vel_target)
        if direction is None:
            synchronize_durations(self.axes)
        else:
            self._plan_along(direction, accel, vel, vel_target)

    def _plan_along(self, u: Vec3, accel: Vec3, vel: Vec3, vel_target: Vec3) -> None:
        line = self._line
        max_jerk = max_accel = max_vel = math.inf
        for axis, ui in zip(self.axes, u, strict=True):
            k = abs(ui)
            if k > FLT_EPSILON:
                max_jerk = min(max_jerk, axis.max_jerk / k)
                max_accel = min(max_accel, axis.max_accel / k)
                max_vel = min(max_vel, axis.max_vel / k)
        line.max_jerk = max_jerk
        line.max_accel = max_accel
        line.max_vel = max_vel
        line.reset(
            accel[0] * u[0] + accel[1] * u[1] + accel[2] * u[2],
            vel[0] * u[0] + vel[1] * u[1] + vel[2] * u[2],
            0.0,
        )
        line.update_durations(vel_target[0] * u[0] + vel_target[1] * u[1] + vel_target[2] * u[2])
        t1, t2, t3 = line.t1, line.t2, line.t3
        jerk = line.first_phase_jerk
        target = line.velocity_target
        for axis, ui in zip(self.axes, u, strict=True):
            axis.follow_profile(t1, t2, t3, jerk * ui, target * ui)

    def update_traj(self, dt: float, time_stretch: float = 1.0) -> None:
        for axis in self.axes:
            axis.update_traj(dt, time_stretch)

    @property
    def total_time(self) -> float:
        return max(axis.total_time for axis in self.axes)

    @property
    def position(self) -> Vec3:
        ax, ay, az = self.axes
        return (ax.pos, ay.pos, az.pos)

    @property
    def velocity(self) -> Vec3:
        ax, ay, az = self.axes
        return (ax.vel, ay.vel, az.vel)

    @property
    def acceleration(self) -> Vec3:
        ax, ay, az = self.axes
        return (ax.accel, ay.accel, az.accel)

    @property
    def jerk(self) -> Vec3:
        ax, ay, az = self.axes
        return (ax.jerk, ay.jerk, az.jerk)

    def point(self) -> TrajectoryPoint:
        ax, ay, az = self.axes
        return TrajectoryPoint(
            (ax.pos, ay.pos, az.pos),
            (ax.vel, ay.vel, az.vel),
            (ax.accel, ay.accel, az.accel),
            (ax.jerk, ay.jerk, az.jerk),
        )
