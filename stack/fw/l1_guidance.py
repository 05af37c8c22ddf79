"""Nonlinear L1 lateral guidance (PX4 ECL ``ECL_L1_Pos_Controller``) on local NED coordinates.

Follows ``src/lib/l1/ECL_L1_Pos_Controller.cpp`` (Park, Deyst, How, "A New Nonlinear Guidance Logic for
Trajectory Tracking", AIAA GNC 2004, with PX4's extensions), but on 2-D local (north, east) metres instead
of lat/lon. The guidance picks a reference point at distance L1 = (damping·period/π)·groundspeed ahead on the
path and commands the lateral acceleration a = K_L1·v²/L1·sin η (K_L1 = 4·damping²) where η is the angle
between the ground velocity and the line to that point; positive a turns right. fw_pos_control flies it as
the bank angle atan(a/g) (``roll_setpoint``); ``lateral_acceleration_ne`` gives it as a vector perpendicular
to the ground velocity.
"""

from __future__ import annotations

import math

from stack.mathlib.scalar import CONSTANTS_ONE_G, FLT_EPSILON, wrap_pi

Vec2 = tuple[float, float]

_HALF_PI = 0.5 * math.pi
_SIN_45 = 0.7071
_BEHIND_A_COS = -0.7071
_PAST_B_ANGLE = math.radians(100.0)
_MIN_GROUND_SPEED = 0.1
_LOITER_OPPOSITE_TANGENT_SPEED = 2.0
_NO_POINT: Vec2 = (math.nan, math.nan)


def _cross(a: Vec2, b: Vec2) -> float:
    return a[0] * b[1] - a[1] * b[0]


def _dot(a: Vec2, b: Vec2) -> float:
    return a[0] * b[0] + a[1] * b[1]


def _unit(a: Vec2) -> Vec2:
    n = math.hypot(a[0], a[1])
    return (a[0] / n, a[1] / n) if n > 0.0 else (0.0, 0.0)


def crosstrack_error(a: Vec2, b: Vec2, position: Vec2) -> float:
    """Signed distance of position from the line A→B [m], positive to the right of the track."""
    ab = _unit((b[0] - a[0], b[1] - a[1]))
    return _cross(ab, (position[0] - a[0], position[1] - a[1]))


class L1Guidance:
    """PX4's L1 guidance: waypoint legs, loiter circles and heading hold in local NED metres.

    Parameters (PX4 fixed-wing names, defaults):
      - ``period`` FW_L1_PERIOD 20 s (7–50): period of the closed-loop lateral response;
      - ``damping`` FW_L1_DAMPING 0.75 (0.6–0.9);
      - ``roll_limit`` FW_R_LIM 50° (35–65), in rad, bounds ``roll_setpoint``;
      - ``roll_slew_rate`` FW_L1_R_SLEW_MAX 90 °/s (0–180, 0 = off), in rad/s.
    Each ``navigate_*`` call updates the outputs: ``lateral_acceleration`` [m/s², + = right],
    ``roll_setpoint`` [rad], ``nav_bearing`` / ``target_bearing`` / ``bearing_error`` [rad],
    ``crosstrack_error`` [m], ``l1_distance`` [m], ``l1_point`` (the point steered to, at L1 along
    ``nav_bearing``; NaN in the heading modes) and ``circle_mode``.
    """

    __slots__ = (
        "_damping",
        "_ground_velocity",
        "_heading_omega",
        "_k_l1",
        "_l1_ratio",
        "_period",
        "bearing_error",
        "circle_mode",
        "crosstrack_error",
        "l1_distance",
        "l1_point",
        "lateral_acceleration",
        "nav_bearing",
        "roll_limit",
        "roll_setpoint",
        "roll_slew_rate",
        "target_bearing",
    )

    def __init__(
        self,
        *,
        period: float = 20.0,
        damping: float = 0.75,
        roll_limit: float = math.radians(50.0),
        roll_slew_rate: float = math.radians(90.0),
    ) -> None:
        self._period = period
        self._damping = damping
        self.set_l1_period(period)
        self.set_l1_damping(damping)
        self.roll_limit = roll_limit
        self.roll_slew_rate = roll_slew_rate
        self.roll_setpoint = 0.0
        self.lateral_acceleration = 0.0
        self.nav_bearing = 0.0
        self.target_bearing = 0.0
        self.bearing_error = 0.0
        self.crosstrack_error = 0.0
        self.l1_distance = 20.0
        self.l1_point: Vec2 = _NO_POINT
        self.circle_mode = False
        self._ground_velocity: Vec2 = (0.0, 0.0)

    def set_l1_period(self, period: float) -> None:
        """FW_L1_PERIOD [s]: sets L1 = damping·period/π · groundspeed and the heading-mode frequency."""
        self._period = period
        self._l1_ratio = self._damping * period / math.pi
        self._heading_omega = math.sqrt(2.0) * math.pi / period

    def set_l1_damping(self, damping: float) -> None:
        """FW_L1_DAMPING: sets the L1 ratio and the gain K_L1 = 4·damping²."""
        self._damping = damping
        self._l1_ratio = damping * self._period / math.pi
        self._k_l1 = 4.0 * damping * damping

    def switch_distance(self, waypoint_radius: float) -> float:
        """Distance at which to switch to the next waypoint: min(acceptance radius, L1)."""
        return min(waypoint_radius, self.l1_distance)

    @property
    def lateral_acceleration_ne(self) -> Vec2:
        """The lateral acceleration as a (north, east) vector, perpendicular to the ground velocity."""
        right = _unit((-self._ground_velocity[1], self._ground_velocity[0]))
        return (self.lateral_acceleration * right[0], self.lateral_acceleration * right[1])

    # -- guidance laws ---------------------------------------------------------------------------

    def navigate_waypoints(
        self, a: Vec2, b: Vec2, position: Vec2, ground_velocity: Vec2, dt: float = 0.0
    ) -> float:
        """Follow the leg A→B; returns the lateral acceleration [m/s²].

        Three cases: farther than L1 from A and more than 135° behind it → fly straight to A;
        already past B (B→vehicle within 100° of A→B) → fly back to B; otherwise track the line
        with η = η1 + η2 (η1 toward the L1 point, limited to 45°; η2 the velocity's angle to the
        line).
        """
        to_b = (b[0] - position[0], b[1] - position[1])
        self.target_bearing = math.atan2(to_b[1], to_b[0])
        ground_speed = max(math.hypot(ground_velocity[0], ground_velocity[1]), _MIN_GROUND_SPEED)
        self.l1_distance = self._l1_ratio * ground_speed

        ab = (b[0] - a[0], b[1] - a[1])
        if math.hypot(ab[0], ab[1]) < 1.0e-6:
            ab = to_b
        ab = _unit(ab)
        a_to_p = (position[0] - a[0], position[1] - a[1])
        self.crosstrack_error = _cross(ab, a_to_p)

        distance_a = math.hypot(a_to_p[0], a_to_p[1])
        along_track = _dot(a_to_p, ab)
        b_to_p_unit = _unit((position[0] - b[0], position[1] - b[1]))
        # Exactly on B the direction from B is undefined (NaN upstream, so not "past B"): track the line.
        on_b = b_to_p_unit == (0.0, 0.0)
        ab_to_bp_angle = math.nan if on_b else math.atan2(_cross(b_to_p_unit, ab), _dot(b_to_p_unit, ab))

        if distance_a > self.l1_distance and along_track / max(distance_a, 1.0) < _BEHIND_A_COS:
            to_a = _unit((-a_to_p[0], -a_to_p[1]))
            eta = math.atan2(_cross(ground_velocity, to_a), _dot(ground_velocity, to_a))
            self.nav_bearing = math.atan2(to_a[1], to_a[0])
        elif abs(ab_to_bp_angle) < _PAST_B_ANGLE:
            to_b_unit = (-b_to_p_unit[0], -b_to_p_unit[1])
            eta = math.atan2(_cross(ground_velocity, to_b_unit), _dot(ground_velocity, to_b_unit))
            self.nav_bearing = math.atan2(to_b_unit[1], to_b_unit[0])
        else:
            eta2 = math.atan2(_cross(ground_velocity, ab), _dot(ground_velocity, ab))
            sine_eta1 = _cross(a_to_p, ab) / max(self.l1_distance, 0.1)
            sine_eta1 = min(max(sine_eta1, -_SIN_45), _SIN_45)
            eta1 = math.asin(sine_eta1)
            eta = eta1 + eta2
            self.nav_bearing = math.atan2(ab[1], ab[0]) + eta1

        eta = min(max(eta, -_HALF_PI), _HALF_PI)
        self.lateral_acceleration = self._k_l1 * ground_speed**2 / self.l1_distance * math.sin(eta)
        self.circle_mode = False
        self.bearing_error = eta
        self._set_l1_point(position)
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_loiter(
        self,
        center: Vec2,
        position: Vec2,
        radius: float,
        direction: int,
        ground_velocity: Vec2,
        dt: float = 0.0,
    ) -> float:
        """Capture and fly a circle (direction +1 clockwise seen from above, −1 counter-clockwise).

        Outside the circle it flies toward the centre with L1 until the circle command (PD on the
        radial error plus the centripetal term v²/r) asks for the tighter turn.
        """
        omega = 2.0 * math.pi / self._period
        k_crosstrack = omega * omega
        k_velocity = 2.0 * self._damping * omega
        ground_speed = max(math.hypot(ground_velocity[0], ground_velocity[1]), _MIN_GROUND_SPEED)
        self.l1_distance = self._l1_ratio * ground_speed

        c_to_p = (position[0] - center[0], position[1] - center[1])
        distance = math.hypot(c_to_p[0], c_to_p[1])
        c_to_p_unit = (c_to_p[0] / distance, c_to_p[1] / distance) if distance > FLT_EPSILON else c_to_p
        # The bearing from the vehicle to the centre (0 at the centre itself, as upstream's geodetic bearing).
        self.target_bearing = math.atan2(center[1] - position[1], center[0] - position[0])

        xtrack_vel_center = _cross(c_to_p_unit, ground_velocity)
        ltrack_vel_center = -_dot(ground_velocity, c_to_p_unit)
        eta = math.atan2(xtrack_vel_center, ltrack_vel_center)
        eta = min(max(eta, -_HALF_PI), _HALF_PI)
        lateral_accel_center = self._k_l1 * ground_speed * ground_speed / self.l1_distance * math.sin(eta)

        xtrack_vel_circle = -ltrack_vel_center
        xtrack_err_circle = distance - radius
        self.crosstrack_error = xtrack_err_circle
        lateral_accel_pd = xtrack_err_circle * k_crosstrack + xtrack_vel_circle * k_velocity
        tangent_vel = xtrack_vel_center * direction
        # Do not let the PD part turn the wrong way while flying the circle backwards.
        if tangent_vel < -_LOITER_OPPOSITE_TANGENT_SPEED and self.circle_mode:
            lateral_accel_pd = max(lateral_accel_pd, 0.0)
        lateral_accel_centripetal = tangent_vel * tangent_vel / max(0.5 * radius, radius + xtrack_err_circle)
        lateral_accel_circle = direction * (lateral_accel_pd + lateral_accel_centripetal)

        capture = xtrack_err_circle > 0.0 and (
            (direction > 0 and lateral_accel_center < lateral_accel_circle)
            or (direction < 0 and lateral_accel_center > lateral_accel_circle)
        )
        if capture:
            self.lateral_acceleration = lateral_accel_center
            self.circle_mode = False
            self.bearing_error = eta
        else:
            self.lateral_acceleration = lateral_accel_circle
            self.circle_mode = True
            self.bearing_error = 0.0
        self.nav_bearing = math.atan2(-c_to_p_unit[1], -c_to_p_unit[0])
        self._set_l1_point(position)
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_heading(
        self, heading_sp: float, heading: float, ground_velocity: Vec2, dt: float = 0.0
    ) -> float:
        """Turn onto a heading (no cross-track term): a = 2·sin η·ω·v with ω = √2·π/period."""
        self.target_bearing = self.nav_bearing = wrap_pi(heading_sp)
        eta = wrap_pi(self.target_bearing - wrap_pi(heading))
        self.bearing_error = eta
        ground_speed = math.hypot(ground_velocity[0], ground_velocity[1])
        self.l1_distance = ground_speed / self._heading_omega
        self.circle_mode = False
        self.crosstrack_error = 0.0
        eta = min(max(eta, -_HALF_PI), _HALF_PI)
        self.lateral_acceleration = 2.0 * math.sin(eta) * ground_speed * self._heading_omega
        self.l1_point = _NO_POINT
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_level_flight(self, heading: float, dt: float = 0.0) -> float:
        """Hold the current heading with zero lateral acceleration."""
        self.target_bearing = self.nav_bearing = heading
        self.bearing_error = 0.0
        self.crosstrack_error = 0.0
        self.lateral_acceleration = 0.0
        self.circle_mode = False
        self.l1_point = _NO_POINT
        self._finish((0.0, 0.0), dt)
        return 0.0

    def _set_l1_point(self, position: Vec2) -> None:
        self.l1_point = (
            position[0] + self.l1_distance * math.cos(self.nav_bearing),
            position[1] + self.l1_distance * math.sin(self.nav_bearing),
        )

    def _finish(self, ground_velocity: Vec2, dt: float) -> None:
        self._ground_velocity = (ground_velocity[0], ground_velocity[1])
        roll = math.atan(self.lateral_acceleration / CONSTANTS_ONE_G)
        roll = min(max(roll, -self.roll_limit), self.roll_limit)
        if dt > 0.0 and self.roll_slew_rate > 0.0:
            step = self.roll_slew_rate * dt
            roll = min(max(roll, self.roll_setpoint - step), self.roll_setpoint + step)
        if math.isfinite(roll):
            self.roll_setpoint = roll
