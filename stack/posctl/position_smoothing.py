"""Smooth waypoint-to-waypoint trajectories for auto modes (PX4 ``PositionSmoothing``).

Follows ``src/lib/motion_planning/PositionSmoothing.cpp`` and ``lib/mathlib/math/TrajMath.hpp`` as
used by ``FlightTaskAuto``. Every cycle, from the current trajectory state and the waypoint
triplet (previous, target, next):

1. a velocity target points at the target, or, while turning onto a new leg, at the point of the
   leg at L1 = max(acceptance radius, 5 m) from the trajectory (``line_crossing_point``) if that is
   short of the target. Once the trajectory has gone beyond a target that the vehicle has not reached
   within the acceptance radius, it comes back and stops there (PX4 aims on along the leg, beyond the
   target, so that the trajectory flies on, away from it, for as long as the target stays);
2. its magnitude is the largest speed from which the vehicle can still slow down, with jerk-limited
   braking, to the speed allowed at the target: v = ½(−b + √(b² − 4c)) with b = 4a²/j and
   c = −2·a·d − v_end². v_end comes from the turn at the target onto the next leg (a circle
   tangent to both legs at the acceptance radius, lateral acceleration MPC_XY_TRAJ_P·MPC_ACC_HOR),
   0 at the last waypoint; the result is capped at the cruise speed (MPC_XY_CRUISE) horizontally
   and at MPC_Z_V_AUTO_UP/DN vertically, keeping the direction so 3-D legs stay straight;
3. three time-synchronised jerk-limited profiles (``VelocitySmoothing3D``) track that target; their
   integration slows by 1 − min(e/MPC_XY_ERR_MAX, 1) while the vehicle lags the trajectory by e.

The output (position, velocity, acceleration, jerk) is kinematically consistent, as
``trajectory_setpoint`` expects.
"""

from __future__ import annotations

import math

from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3, line_crossing_point
from stack.params.binding import ParamSet
from stack.posctl.velocity_smoothing import TrajectoryPoint, VelocitySmoothing3D

Waypoints = tuple[Vec3, Vec3, Vec3]

_MIN_CROSSING_DISTANCE = 5.0
_TURNING_MIN_SPEED = 0.2
_TURNING_COS_ALIGN = 0.98
_SAME_WAYPOINT = 0.001
_CLAMP_TOLERANCE = 0.5


def max_speed_from_distance(jerk: float, accel: float, braking_distance: float, final_speed: float) -> float:
    """Largest speed from which ``final_speed`` is reached within ``braking_distance`` (TrajMath).

    Assumes constant deceleration ``accel`` after a delay of 2·accel/jerk for the acceleration to
    swing over: v² = v_end² + 2·a·(d − 2·v·a/j). Never below ``final_speed``.
    """
    b = 4.0 * accel * accel / jerk
    c = -2.0 * accel * braking_distance - final_speed * final_speed
    return max(0.5 * (-b + math.sqrt(b * b - 4.0 * c)), final_speed)


def max_speed_in_turn(alpha: float, accel: float, radius: float) -> float:
    """Speed on the circle tangent to two legs at ``radius`` from their corner (TrajMath).

    alpha is the angle between the legs as seen from the corner (π = straight on, 0 = reversal);
    the circle radius is radius·tan(α/2), and v² = accel·circle radius.
    """
    return math.sqrt(accel * radius * math.tan(0.5 * alpha))


def _unit2(x: float, y: float) -> tuple[float, float]:
    n = math.hypot(x, y)
    return (x / n, y / n) if n > FLT_EPSILON else (0.0, 0.0)


def _beyond(point: Vec3, previous: Vec3, target: Vec3) -> bool:
    """Whether ``point`` lies past ``target`` along the leg from ``previous`` (horizontally)."""
    return (point[0] - target[0]) * (target[0] - previous[0]) + (point[1] - target[1]) * (target[1] - previous[1]) > 0.0


def _angle_at_corner(ux: float, uy: float, wx: float, wy: float) -> float:
    """Angle between the unit 2-D vectors u and w, kept below π so tan(α/2) stays finite."""
    d = ux * wx + uy * wy
    alpha = math.acos(min(max(d, -1.0), 1.0))
    return min(alpha, math.pi - FLT_EPSILON)


class PositionSmoothingParams(ParamSet):
    """Tunables of ``PositionSmoothing`` (the catalogue's). ``mpc_xy_vel_max`` is the per-axis horizontal speed
    limit of the profiles, ``mpc_xy_traj_p`` the share of MPC_ACC_HOR used as lateral acceleration in turns;
    ``nav_acc_rad`` is the navigator's horizontal acceptance radius (a mission item's own when it has one)."""

    mpc_xy_cruise: float
    mpc_xy_vel_max: float
    mpc_z_v_auto_up: float
    mpc_z_v_auto_dn: float
    mpc_acc_hor: float
    mpc_acc_up_max: float
    mpc_acc_down_max: float
    mpc_jerk_auto: float
    mpc_xy_err_max: float
    mpc_xy_traj_p: float
    nav_acc_rad: float
    nav_mc_alt_rad: float


class PositionSmoothing:
    """Jerk-limited trajectory through a waypoint triplet (PX4 ``PositionSmoothing``).

    Call ``reset`` with the vehicle state when the auto mode starts, then ``generate`` once per
    cycle. Waypoints must be finite NED positions; pass the target again as "next" (or use
    ``stop_at_target``) to stop at it, and ``is_single_waypoint`` to fly straight at it ignoring
    the previous leg. ``unsmoothed_velocity`` holds the last velocity target before smoothing.
    """

    __slots__ = ("_max_speed_previous", "_params", "_trajectory", "unsmoothed_velocity")

    def __init__(self, params: PositionSmoothingParams | None = None) -> None:
        self._trajectory = VelocitySmoothing3D()
        self._max_speed_previous = 0.0
        self.unsmoothed_velocity: Vec3 = (0.0, 0.0, 0.0)
        self.set_params(params or PositionSmoothingParams())

    def set_params(self, params: PositionSmoothingParams) -> None:
        self._params = params
        jerk = params.mpc_jerk_auto
        self._trajectory.set_limits(
            max_jerk=(jerk, jerk, jerk),
            max_accel=(params.mpc_acc_hor, params.mpc_acc_hor, params.mpc_acc_up_max),
            max_vel=(params.mpc_xy_vel_max, params.mpc_xy_vel_max, params.mpc_z_v_auto_up),
        )

    @property
    def params(self) -> PositionSmoothingParams:
        return self._params

    def reset(self, pos: Vec3, vel: Vec3, acc: Vec3) -> None:
        """Restart the trajectory from the given state.

        The speed held through a turn starts at the current horizontal speed, so a reset while
        turning keeps flying instead of braking to a stop.
        """
        self._trajectory.reset(acc, vel, pos)
        self._max_speed_previous = math.hypot(vel[0], vel[1])

    def point(self) -> TrajectoryPoint:
        """The current trajectory state."""
        return self._trajectory.point()

    def reached(self, target: Vec3, position: Vec3 | None = None) -> bool:
        """Whether position (default: the trajectory's) is within NAV_ACC_RAD horizontally and
        NAV_MC_ALT_RAD vertically of target."""
        p = self._trajectory.position if position is None else position
        return (
            math.hypot(target[0] - p[0], target[1] - p[1]) <= self._params.nav_acc_rad
            and abs(target[2] - p[2]) <= self._params.nav_mc_alt_rad
        )

    def generate(
        self,
        dt: float,
        current_position: Vec3,
        waypoints: Waypoints,
        *,
        is_single_waypoint: bool = False,
        stop_at_target: bool = False,
    ) -> TrajectoryPoint:
        """Advance the trajectory by dt toward ``waypoints = (previous, target, next)``.

        Returns the new setpoint; the plan for the following cycle is made from it.
        """
        previous, target, following = waypoints
        if stop_at_target or is_single_waypoint or _beyond(self._trajectory.position, previous, target):
            following = target
        if is_single_waypoint:
            previous = target

        self._select_vertical_limits(target)
        velocity_target = self._velocity_target(previous, target, following, is_single_waypoint)
        self.unsmoothed_velocity = velocity_target

        trajectory = self._trajectory
        trajectory.update_traj(dt, self._time_stretch(current_position))
        out = trajectory.point()
        trajectory.update_durations(velocity_target)
        return out

    # -- internals -------------------------------------------------------------------------------

    def _select_vertical_limits(self, target: Vec3) -> None:
        z_axis = self._trajectory.axes[2]
        if target[2] < z_axis.pos:
            z_axis.max_vel = self._params.mpc_z_v_auto_up
            z_axis.max_accel = self._params.mpc_acc_up_max
        else:
            z_axis.max_vel = self._params.mpc_z_v_auto_dn
            z_axis.max_accel = self._params.mpc_acc_down_max

    def _time_stretch(self, position: Vec3) -> float:
        x_axis, y_axis, _ = self._trajectory.axes
        ex = x_axis.pos - position[0]
        ey = y_axis.pos - position[1]
        err_max = self._params.mpc_xy_err_max
        # Stretch only when the vehicle is behind the trajectory, never when it is ahead.
        if err_max <= FLT_EPSILON or ex * x_axis.vel + ey * y_axis.vel < 0.0:
            return 1.0
        return 1.0 - min(math.hypot(ex, ey) / err_max, 1.0)

    def _is_turning(self, target: Vec3) -> bool:
        x_axis, y_axis, _ = self._trajectory.axes
        vx, vy = x_axis.vel, y_axis.vel
        dx, dy = target[0] - x_axis.pos, target[1] - y_axis.pos
        ux, uy = _unit2(vx, vy)
        tx, ty = _unit2(dx, dy)
        return (
            math.hypot(vx, vy) > _TURNING_MIN_SPEED
            and ux * tx + uy * ty < _TURNING_COS_ALIGN
            and math.hypot(dx, dy) > self._params.nav_acc_rad
        )

    def _velocity_target(self, previous: Vec3, target: Vec3, following: Vec3, single: bool) -> Vec3:
        pos = self._trajectory.position
        turning = not single and self._is_turning(target)
        aim = target
        if turning:
            distance = max(self._params.nav_acc_rad, _MIN_CROSSING_DISTANCE)
            crossing = line_crossing_point(previous, target, pos, distance)
            # Never beyond the target on its leg: a trajectory that has gone past a target the vehicle has not
            # reached yet would otherwise follow the leg on, away from it, for as long as the target stays.
            if not _beyond(crossing, previous, target):
                aim = crossing

        xy_speed = self._max_xy_speed(pos, target, following)
        if turning:
            xy_speed = min(self._max_speed_previous, xy_speed)
        else:
            self._max_speed_previous = xy_speed
        z_speed = self._max_z_speed(pos, target, following)

        dx, dy, dz = aim[0] - pos[0], aim[1] - pos[1], aim[2] - pos[2]
        n = math.sqrt(dx * dx + dy * dy + dz * dz)
        if n <= FLT_EPSILON:
            return (0.0, 0.0, 0.0)
        # Along the direction to the aim point, as fast as both the xy and the z limit allow;
        # components below the clamp tolerance are left alone (PX4 clampToXYNorm/clampToZNorm).
        scale = math.hypot(xy_speed, z_speed) / n
        n_xy = math.hypot(dx, dy) * scale
        if n_xy > xy_speed and n_xy > _CLAMP_TOLERANCE:
            scale *= xy_speed / n_xy
        n_z = abs(dz) * scale
        if n_z > z_speed and n_z > _CLAMP_TOLERANCE:
            scale *= z_speed / n_z
        return (dx * scale, dy * scale, dz * scale)

    def _speed_from_leg(self, start: Vec3, target: Vec3, following: Vec3, exit_speed: float) -> float:
        p = self._params
        tnx, tny = target[0] - following[0], target[1] - following[1]
        distance_target_next = math.hypot(tnx, tny)
        speed_at_target = 0.0
        if distance_target_next > _SAME_WAYPOINT and distance_target_next >= p.nav_acc_rad:
            ux, uy = _unit2(target[0] - start[0], target[1] - start[1])
            wx, wy = tnx / distance_target_next, tny / distance_target_next
            alpha = _angle_at_corner(ux, uy, wx, wy)
            turn_speed = max_speed_in_turn(alpha, p.mpc_xy_traj_p * p.mpc_acc_hor, p.nav_acc_rad)
            speed_at_target = min(turn_speed, exit_speed, p.mpc_xy_cruise)
        distance = math.hypot(start[0] - target[0], start[1] - target[1])
        speed = max_speed_from_distance(p.mpc_jerk_auto, p.mpc_acc_hor, distance, speed_at_target)
        return min(p.mpc_xy_cruise, speed)

    def _max_xy_speed(self, pos: Vec3, target: Vec3, following: Vec3) -> float:
        # Backwards over the legs: the speed allowed when starting the last leg limits the speed
        # at its corner, which limits the speed now.
        exit_speed = self._speed_from_leg(target, following, following, 0.0)
        return self._speed_from_leg(pos, target, following, exit_speed)

    def _max_z_speed(self, pos: Vec3, target: Vec3, following: Vec3) -> float:
        z_axis = self._trajectory.axes[2]
        arrival_speed = 0.0
        if abs(target[2] - following[2]) > _SAME_WAYPOINT:
            # The corner seen in the vertical plane of the path: (horizontal distance, altitude).
            leg_in = math.hypot(target[0] - pos[0], target[1] - pos[1])
            leg_out = math.hypot(following[0] - target[0], following[1] - target[1])
            ux, uz = _unit2(leg_in, target[2] - pos[2])
            wx, wz = _unit2(-leg_out, target[2] - following[2])
            alpha = _angle_at_corner(ux, uz, wx, wz)
            turn_speed = max_speed_in_turn(alpha, z_axis.max_accel, self._params.nav_mc_alt_rad)
            arrival_speed = min(turn_speed, z_axis.max_vel)
        distance = abs(target[2] - pos[2])
        speed = max_speed_from_distance(z_axis.max_jerk, z_axis.max_accel, distance, arrival_speed)
        return min(z_axis.max_vel, speed)
