"""Nonlinear Path Following Guidance with excess wind handling (PX4 ``NPFG``), in local NED metres.

Follows ``src/lib/npfg/npfg.cpp`` of PX4 v1.13/v1.14 (T. Stastny and R. Siegwart, "On Flying Backwards:
Preventing Run-away of Small, Low-speed, Fixed-wing UAVs in Strong Winds", IROS 2019; T. Stastny,
"Low-Altitude Control and Local Re-Planning Strategies for Small Fixed-Wing UAVs", ETH thesis 2020):

- The track error is normalised by a bound that grows with the ground speed, e_b = V_g·T (T = period·
  damping); the look-ahead angle (π/2)·(1 − e/e_b)² turns the bearing from the track normal (far
  away) to the path tangent (on the track).
- The bearing's feasibility in the wind (continuous, 0…1) decides the air-velocity reference: the wind
  triangle solved at the nominal airspeed when feasible; otherwise the airspeed is raised (up to the
  maximum) to hold the bearing, to keep a minimum forward ground speed (FW_GND_SPD_MIN) or to return
  to the track (track keeping), and when even the maximum cannot hold it the vehicle turns into the
  wind so that it never runs away downwind.
- Lateral acceleration a = k·(V_a × V_a,ref)/|V_a,ref| with k = 4π·damping/period, the full gain at
  heading errors beyond 90°, plus the curvature feed-forward ramped in near the track; the period is
  bounded below for the roll response (FW_NPFG_ROLL_TC, safety factor FW_NPFG_PERIOD_SF) and above for
  track keeping on curved paths in wind.

The API mirrors :class:`stack.fw.l1_guidance.L1Guidance` (same method names and arguments, plus the
wind estimate as the keyword ``wind``; a non-finite wind counts as none), so a position controller can
switch between the two on FW_USE_NPFG. Output attributes as L1's: ``lateral_acceleration`` [m/s², + =
right], ``roll_setpoint``, ``nav_bearing`` (the bearing vector), ``target_bearing`` (the path tangent),
``bearing_error`` (from the air velocity to its reference), ``crosstrack_error`` (lines: + = right of the
track; loiter: distance − radius) and ``circle_mode``; NPFG's own: ``airspeed_reference`` (the true
airspeed it asks for), ``heading_reference``, ``track_error_bound``, ``adapted_period``,
``bearing_feasibility`` (and ``_on_track``), ``min_ground_speed_reference``, ``track_proximity``.
"""

from __future__ import annotations

import math

from stack.mathlib.scalar import CONSTANTS_ONE_G, constrain
from stack.params.binding import ParamSet

Vec2 = tuple[float, float]

EPSILON = 1.0e-6
MIN_RADIUS = 0.5
"""Smallest effective loiter radius [m] (avoids singularities)."""
NTE_FRACTION = 0.5
"""Normalised track error at which track keeping asks for its full minimum ground speed."""
AIRSPEED_BUFFER = 1.5
"""Width [m/s] of the feasibility transition (no jumps in the airspeed reference near infeasibility)."""
_CENTRE_DISTANCE = 0.1
_ZERO: Vec2 = (0.0, 0.0)


def _cross(a: Vec2, b: Vec2) -> float:
    return a[0] * b[1] - a[1] * b[0]


def _dot(a: Vec2, b: Vec2) -> float:
    return a[0] * b[0] + a[1] * b[1]


def _norm(a: Vec2) -> float:
    return math.hypot(a[0], a[1])


def _unit(a: Vec2) -> Vec2:
    n = _norm(a)
    return (a[0] / n, a[1] / n) if n > 0.0 else _ZERO


def _finite_or_zero(v: Vec2) -> Vec2:
    return (v[0], v[1]) if math.isfinite(v[0]) and math.isfinite(v[1]) else _ZERO


class NpfgParams(ParamSet):
    """NPFG's settings (the catalogue's FW_NPFG_*, and PX4 v1.13's FW_L1_R_SLEW_MAX, shared between L1 and NPFG);
    FW_AIRSPD_TRIM is the initial nominal airspeed reference (see :meth:`NPFG.set_airspeed_limits`)."""

    fw_npfg_period: float
    fw_npfg_damping: float
    fw_npfg_lb_period: int
    fw_npfg_ub_period: int
    fw_npfg_track_keep: int
    fw_npfg_en_min_gsp: int
    fw_npfg_wind_reg: int
    fw_npfg_gsp_max_tk: float
    fw_npfg_roll_tc: float
    fw_npfg_sw_dst_mlt: float
    fw_npfg_period_sf: float
    fw_gnd_spd_min: float
    fw_r_lim: float
    fw_l1_r_slew_max: float
    fw_airspd_trim: float
    fw_airspd_max: float


class NPFG:
    """PX4's NPFG: waypoint legs, loiter circles, heading and bearing hold in local NED metres."""

    def __init__(self, params: NpfgParams) -> None:
        self.set_params(params)
        self.airspeed_nominal = max(params.fw_airspd_trim, 0.1)
        self.airspeed_max = max(params.fw_airspd_max, 0.1)
        self.time_constant = self._period * self._damping
        self.adapted_period = self._period
        self.p_gain = 4.0 * math.pi * self._damping / self._period
        self.track_error_bound = 0.0
        self.track_proximity = 0.0
        self.bearing_feasibility = 1.0
        self.bearing_feasibility_on_track = 1.0
        self.min_ground_speed_reference = 0.0
        self.airspeed_reference = self.airspeed_nominal
        self._air_vel_ref: Vec2 = (self.airspeed_nominal, 0.0)
        self.lateral_acceleration = 0.0
        self.lateral_acceleration_ff = 0.0
        self.roll_setpoint = 0.0
        self.nav_bearing = 0.0
        self.target_bearing = 0.0
        self.bearing_error = 0.0
        self.crosstrack_error = 0.0
        self.circle_mode = False
        self._ground_velocity: Vec2 = _ZERO

    def set_params(self, params: NpfgParams) -> None:
        self.params = params
        self._period = max(params.fw_npfg_period, EPSILON)
        self._damping = constrain(params.fw_npfg_damping, EPSILON, 1.0)

    def set_airspeed_limits(self, nominal: float, maximum: float) -> None:
        """The nominal and maximum true airspeeds the reference may use [m/s] (PX4 sets them every step
        from FW_AIRSPD_TRIM and FW_AIRSPD_MAX times EAS→TAS)."""
        if math.isfinite(nominal) and math.isfinite(maximum):
            self.airspeed_nominal = max(nominal, 0.1)
            self.airspeed_max = max(maximum, 0.1)

    def switch_distance(self, waypoint_radius: float) -> float:
        """Distance at which to switch to the next waypoint: min(acceptance radius, FW_NPFG_SW_DST_MLT·bound)."""
        return min(waypoint_radius, self.track_error_bound * self.params.fw_npfg_sw_dst_mlt)

    @property
    def heading_reference(self) -> float:
        """Heading of the air-velocity reference [rad]."""
        return math.atan2(self._air_vel_ref[1], self._air_vel_ref[0])

    @property
    def lateral_acceleration_ne(self) -> Vec2:
        """The lateral acceleration as a (north, east) vector, perpendicular to the ground velocity."""
        right = _unit((-self._ground_velocity[1], self._ground_velocity[0]))
        return (self.lateral_acceleration * right[0], self.lateral_acceleration * right[1])

    # -- guidance laws ---------------------------------------------------------------------------

    def navigate_waypoints(
        self, a: Vec2, b: Vec2, position: Vec2, ground_velocity: Vec2, dt: float = 0.0, *, wind: Vec2 = _ZERO
    ) -> float:
        """Follow the leg A→B; returns the lateral acceleration [m/s²].

        In front of A (behind it as seen along A→B) it flies to A until the bearing to the line is
        shallower than the bearing to A; with A on B, or past B, it flies to B (PX4's
        ``FixedwingPositionControl::navigateWaypoints``: a leg whose end was passed without the switch, a
        climb-out that overflew the first waypoint below its altitude, would otherwise be followed for ever).
        """
        wind = _finite_or_zero(wind)
        ab = (b[0] - a[0], b[1] - a[1])
        a_to_p = (position[0] - a[0], position[1] - a[1])
        past_b = _dot(ab, (position[0] - b[0], position[1] - b[1])) > EPSILON
        if _norm(ab) < EPSILON or past_b:
            tangent = _unit((b[0] - position[0], b[1] - position[1]))
            self._evaluate(ground_velocity, wind, tangent, 0.0, 0.0)
            self.crosstrack_error = 0.0
        else:
            tangent = _unit(ab)
            track_error = _cross(tangent, a_to_p)
            to_a = _unit((-a_to_p[0], -a_to_p[1])) if _dot(ab, a_to_p) < 0.0 else None
            self._evaluate(ground_velocity, wind, tangent, track_error, 0.0, to_a)
            self.crosstrack_error = track_error
        self.circle_mode = False
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
        *,
        wind: Vec2 = _ZERO,
    ) -> float:
        """Fly a circle (direction +1 clockwise seen from above, −1 counter-clockwise)."""
        wind = _finite_or_zero(wind)
        radius = max(radius, MIN_RADIUS)
        direction = 1 if direction >= 0 else -1
        c_to_p = (position[0] - center[0], position[1] - center[1])
        distance = _norm(c_to_p)
        if distance < _CENTRE_DISTANCE:
            # At the centre any point of the circle is the closest: take the one ahead (or north).
            to_closest = _unit(ground_velocity) if _norm(ground_velocity) >= 0.1 else (1.0, 0.0)
        else:
            to_closest = (c_to_p[0] / distance, c_to_p[1] / distance)
        tangent = (-direction * to_closest[1], direction * to_closest[0])
        track_error = -direction * (distance - radius)
        self._evaluate(ground_velocity, wind, tangent, track_error, direction / radius)
        self.crosstrack_error = distance - radius
        self.circle_mode = self.track_proximity > EPSILON
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_heading(
        self, heading_sp: float, heading: float, ground_velocity: Vec2, dt: float = 0.0, *, wind: Vec2 = _ZERO
    ) -> float:
        """Turn onto a heading (air-mass relative, no cross-track term).

        PX4 regulates the air velocity (ground − wind) onto the heading; here its direction is the
        vehicle's ``heading`` (no sideslip), so the law needs no wind estimate for the direction.
        """
        wind = _finite_or_zero(wind)
        air = (ground_velocity[0] - wind[0], ground_velocity[1] - wind[1])
        if math.isfinite(heading):
            airspeed = _norm(air)
            air = (airspeed * math.cos(heading), airspeed * math.sin(heading))
        self._evaluate(air, _ZERO, (math.cos(heading_sp), math.sin(heading_sp)), 0.0, 0.0)
        self.crosstrack_error = 0.0
        self.circle_mode = False
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_bearing(
        self, bearing: float, ground_velocity: Vec2, dt: float = 0.0, *, wind: Vec2 = _ZERO
    ) -> float:
        """Hold a ground course (no cross-track term)."""
        wind = _finite_or_zero(wind)
        self._evaluate(ground_velocity, wind, (math.cos(bearing), math.sin(bearing)), 0.0, 0.0)
        self.crosstrack_error = 0.0
        self.circle_mode = False
        self._finish(ground_velocity, dt)
        return self.lateral_acceleration

    def navigate_level_flight(self, heading: float, dt: float = 0.0) -> float:
        """Keep the wings level on the current heading."""
        self.airspeed_reference = self.airspeed_nominal
        self._air_vel_ref = (self.airspeed_nominal * math.cos(heading), self.airspeed_nominal * math.sin(heading))
        self.lateral_acceleration = 0.0
        self.bearing_feasibility = 1.0
        self.nav_bearing = self.target_bearing = heading
        self.bearing_error = 0.0
        self.crosstrack_error = 0.0
        self.circle_mode = False
        self._finish(_ZERO, dt)
        return 0.0

    # -- the law (PX4 NPFG::evaluate) --------------------------------------------------------------

    def _evaluate(
        self,
        ground_vel: Vec2,
        wind_vel: Vec2,
        tangent: Vec2,
        signed_track_error: float,
        curvature: float,
        bearing_to_point: Vec2 | None = None,
    ) -> None:
        ground_speed = _norm(ground_vel)
        air_vel = (ground_vel[0] - wind_vel[0], ground_vel[1] - wind_vel[1])
        airspeed = _norm(air_vel)
        wind_speed = _norm(wind_vel)
        track_error = abs(signed_track_error)

        # The bound uses the previous step's time constant; the period adapts below.
        self.track_error_bound = self._track_error_bound(ground_speed, self.time_constant)
        normalised = self._normalised_track_error(track_error, self.track_error_bound)
        look_ahead = self._look_ahead_angle(normalised)
        bearing = self._bearing_vector(tangent, look_ahead, signed_track_error)
        wind_cross_upt = _cross(wind_vel, tangent)
        wind_dot_upt = _dot(wind_vel, tangent)
        self.bearing_feasibility_on_track = self._bearing_feasibility(
            wind_cross_upt, wind_dot_upt, airspeed, wind_speed
        )
        self._adapt(ground_speed, airspeed, wind_speed, track_error, curvature)

        if bearing_to_point is not None and _dot(tangent, bearing) < _dot(tangent, bearing_to_point):
            # In front of the first waypoint, and the bearing to it is shallower than to the line: fly to
            # the waypoint as if on a track through it.
            signed_track_error = 0.0
            tangent = bearing = bearing_to_point
            look_ahead = 0.0
            wind_cross_upt = _cross(wind_vel, tangent)
            wind_dot_upt = _dot(wind_vel, tangent)
            self.bearing_feasibility_on_track = self._bearing_feasibility(
                wind_cross_upt, wind_dot_upt, airspeed, wind_speed
            )
            self._adapt(ground_speed, airspeed, wind_speed, track_error, curvature)

        self.track_proximity = math.sin(look_ahead) ** 2
        wind_cross_bearing = _cross(wind_vel, bearing)
        wind_dot_bearing = _dot(wind_vel, bearing)
        self.bearing_feasibility = self._bearing_feasibility(wind_cross_bearing, wind_dot_bearing, airspeed, wind_speed)
        feasibility = self.bearing_feasibility * self.bearing_feasibility_on_track
        self.min_ground_speed_reference = self._min_ground_speed(normalised, feasibility)
        self._air_vel_ref = self._reference_air_velocity(
            wind_vel, bearing, wind_cross_bearing, wind_dot_bearing, wind_speed, self.min_ground_speed_reference
        )
        self.airspeed_reference = _norm(self._air_vel_ref)
        lateral_accel = self._lateral_accel(air_vel, airspeed)
        self.lateral_acceleration_ff = self._lateral_accel_ff(
            tangent, ground_vel, wind_dot_upt, wind_cross_upt, airspeed, signed_track_error, curvature
        )
        # The curvature feed-forward comes in near the track and fades as the bearing becomes infeasible.
        self.lateral_acceleration = lateral_accel + feasibility * self.track_proximity * self.lateral_acceleration_ff
        self.nav_bearing = math.atan2(bearing[1], bearing[0])
        self.target_bearing = math.atan2(tangent[1], tangent[0])
        self.bearing_error = math.atan2(_cross(air_vel, self._air_vel_ref), _dot(air_vel, self._air_vel_ref))

    def _adapt(
        self, ground_speed: float, airspeed: float, wind_speed: float, track_error: float, curvature: float
    ) -> None:
        self.adapted_period = self._adapt_period(ground_speed, airspeed, wind_speed, track_error, curvature)
        self.p_gain = 4.0 * math.pi * self._damping / self.adapted_period
        self.time_constant = self.adapted_period * self._damping

    def _adapt_period(
        self, ground_speed: float, airspeed: float, wind_speed: float, track_error: float, curvature: float
    ) -> float:
        p = self.params
        period = self._period
        if not p.fw_npfg_lb_period:
            return period
        air_turn_rate = abs(curvature * airspeed)
        wind_factor = self._wind_factor(airspeed, wind_speed)
        feas_on_track = self.bearing_feasibility_on_track
        period_lb = self._period_lower_bound(air_turn_rate, wind_factor, feas_on_track) * p.fw_npfg_period_sf
        period = max(period_lb, period)
        # Upper bounding only with lower bounding: shortening the period without it can destabilise.
        period_ub = self._period_upper_bound(air_turn_rate, wind_factor, feas_on_track)
        if p.fw_npfg_ub_period and math.isfinite(period_ub) and period > period_ub:
            period_adapted = max(period_lb, period_ub)
            time_constant = period * self._damping
            bound = self._track_error_bound(ground_speed, time_constant)
            look_ahead = self._look_ahead_angle(self._normalised_track_error(track_error, bound))
            proximity = math.sin(look_ahead) ** 2
            # From the nominal period far from the track to the adapted one on it.
            period = period_adapted * proximity + (1.0 - proximity) * period
        return period

    @staticmethod
    def _normalised_track_error(track_error: float, bound: float) -> float:
        return constrain(track_error / bound, 0.0, 1.0) if bound > 0.0 else 1.0

    @staticmethod
    def _wind_factor(airspeed: float, wind_speed: float) -> float:
        if wind_speed > airspeed or airspeed < EPSILON:
            return 2.0
        return 2.0 * (1.0 - math.sqrt(1.0 - min(1.0, wind_speed / airspeed)))

    def _period_upper_bound(self, air_turn_rate: float, wind_factor: float, feas_on_track: float) -> float:
        denominator = air_turn_rate * wind_factor * feas_on_track
        if air_turn_rate * wind_factor > EPSILON and denominator > 0.0:
            return 4.0 * math.pi * self._damping / denominator
        return math.inf

    def _period_lower_bound(self, air_turn_rate: float, wind_factor: float, feas_on_track: float) -> float:
        """Marginal stability against the roll response lag (a conservative worst case)."""
        roll_tc = self.params.fw_npfg_roll_tc
        period_lb = math.pi * roll_tc / self._damping
        if air_turn_rate * wind_factor < EPSILON or self._damping < 0.5:
            return period_lb
        windy_curved = 4.0 * math.pi * roll_tc * self._damping
        return windy_curved * feas_on_track + (1.0 - feas_on_track) * period_lb

    @staticmethod
    def _track_error_bound(ground_speed: float, time_constant: float) -> float:
        if ground_speed > 1.0:
            return ground_speed * time_constant
        # Below 1 m/s a smooth floor keeps the normalisation away from zero.
        return 0.5 * time_constant * (ground_speed * ground_speed + 1.0)

    @staticmethod
    def _look_ahead_angle(normalised_track_error: float) -> float:
        return 0.5 * math.pi * (normalised_track_error - 1.0) ** 2

    @staticmethod
    def _bearing_vector(tangent: Vec2, look_ahead: float, signed_track_error: float) -> Vec2:
        normal = (-tangent[1], tangent[0])  # 90° clockwise: to the right of the path
        sign = -1.0 if signed_track_error < 0.0 else 1.0
        to_track = (-sign * normal[0], -sign * normal[1])
        c, s = math.cos(look_ahead), math.sin(look_ahead)
        return (c * to_track[0] + s * tangent[0], c * to_track[1] + s * tangent[1])

    @staticmethod
    def _bearing_feasibility(
        wind_cross_bearing: float, wind_dot_bearing: float, airspeed: float, wind_speed: float
    ) -> float:
        cross = wind_speed if wind_dot_bearing < 0.0 else abs(wind_cross_bearing)
        s = math.sin(0.5 * math.pi * constrain((airspeed - cross) / AIRSPEED_BUFFER, 0.0, 1.0))
        return s * s

    @staticmethod
    def _bearing_is_feasible(
        wind_cross_bearing: float, wind_dot_bearing: float, airspeed: float, wind_speed: float
    ) -> bool:
        return abs(wind_cross_bearing) < airspeed and (wind_dot_bearing > 0.0 or wind_speed < airspeed)

    def _min_ground_speed(self, normalised_track_error: float, feasibility: float) -> float:
        p = self.params
        track_keeping = 0.0
        if p.fw_npfg_track_keep and p.fw_npfg_wind_reg:
            track_keeping = (
                (1.0 - feasibility)
                * p.fw_npfg_gsp_max_tk
                * constrain(normalised_track_error / NTE_FRACTION, 0.0, 1.0)
            )
        desired = max(p.fw_gnd_spd_min, 0.0) if p.fw_npfg_en_min_gsp and p.fw_npfg_wind_reg else 0.0
        return max(track_keeping, desired)

    def _reference_air_velocity(
        self,
        wind_vel: Vec2,
        bearing: Vec2,
        wind_cross_bearing: float,
        wind_dot_bearing: float,
        wind_speed: float,
        min_ground_speed: float,
    ) -> Vec2:
        p = self.params
        nominal, maximum = self.airspeed_nominal, self.airspeed_max
        feasible = self._bearing_is_feasible
        if (
            min_ground_speed > wind_dot_bearing
            and (p.fw_npfg_en_min_gsp or p.fw_npfg_track_keep)
            and p.fw_npfg_wind_reg
        ):
            # The airspeed that gives the minimum ground speed along the bearing.
            airspeed_min = math.hypot(min_ground_speed - wind_dot_bearing, wind_cross_bearing)
            if airspeed_min > maximum:
                if feasible(wind_cross_bearing, wind_dot_bearing, maximum, wind_speed):
                    return self._solve_wind_triangle(wind_cross_bearing, maximum, bearing)
                return self._infeasible_air_velocity(wind_vel, bearing, wind_speed, maximum)
            return self._solve_wind_triangle(wind_cross_bearing, max(airspeed_min, nominal), bearing)
        if feasible(wind_cross_bearing, wind_dot_bearing, nominal, wind_speed):
            return self._solve_wind_triangle(wind_cross_bearing, nominal, bearing)
        if p.fw_npfg_wind_reg and feasible(wind_cross_bearing, wind_dot_bearing, maximum, wind_speed):
            if wind_dot_bearing <= 0.0:
                # Regulate, not overcome, the excess head wind: fly into it at the wind speed (at worst
                # zero ground speed). PX4's code assigns +wind here, which points downwind; its own note
                # (zero ground velocity in the end) needs −wind.
                return (-wind_vel[0], -wind_vel[1])
            # Square to the bearing: the least airspeed that holds it.
            return (-wind_cross_bearing * bearing[1], wind_cross_bearing * bearing[0])
        return self._infeasible_air_velocity(
            wind_vel, bearing, wind_speed, maximum if p.fw_npfg_wind_reg else nominal
        )

    @staticmethod
    def _solve_wind_triangle(wind_cross_bearing: float, airspeed: float, bearing: Vec2) -> Vec2:
        """The air velocity of magnitude ``airspeed`` whose sum with the wind lies along ``bearing``."""
        along = math.sqrt(max(airspeed * airspeed - wind_cross_bearing * wind_cross_bearing, 0.0))
        return (
            along * bearing[0] - wind_cross_bearing * bearing[1],
            wind_cross_bearing * bearing[0] + along * bearing[1],
        )

    @staticmethod
    def _infeasible_air_velocity(wind_vel: Vec2, bearing: Vec2, wind_speed: float, airspeed: float) -> Vec2:
        """Into the wind, turned toward the bearing as far as the excess wind allows: no run-away."""
        k = math.sqrt(max(wind_speed * wind_speed - airspeed * airspeed, 0.0))
        direction = _unit((k * bearing[0] - wind_vel[0], k * bearing[1] - wind_vel[1]))
        return (direction[0] * airspeed, direction[1] * airspeed)

    def _lateral_accel(self, air_vel: Vec2, airspeed: float) -> float:
        ref = self._air_vel_ref
        cross = _cross(air_vel, ref)
        if _dot(air_vel, ref) < 0.0:
            # Beyond 90° of heading error: the full turn.
            return self.p_gain * (-airspeed if cross < 0.0 else airspeed)
        if self.airspeed_reference < EPSILON:
            return 0.0
        # Divided by the reference airspeed: the command at the present airspeed.
        return self.p_gain * cross / self.airspeed_reference

    @staticmethod
    def _lateral_accel_ff(
        tangent: Vec2,
        ground_vel: Vec2,
        wind_dot_upt: float,
        wind_cross_upt: float,
        airspeed: float,
        signed_track_error: float,
        curvature: float,
    ) -> float:
        """The lateral acceleration that keeps a curved track, evaluated at the closest point as if on it."""
        # The curvature of the concentric path through the vehicle.
        path_frame_curvature = curvature / max(1.0 - curvature * signed_track_error, abs(curvature) * MIN_RADIUS)
        tangent_ground_speed = max(_dot(ground_vel, tangent), 0.0)
        path_frame_rate = path_frame_curvature * tangent_ground_speed
        air_along = math.sqrt(max(airspeed * airspeed - wind_cross_upt * wind_cross_upt, 0.0))
        speed_ratio = 1.0 + wind_dot_upt / max(air_along, EPSILON)
        # airspeed·ratio rather than ground speed²: the acceleration is commanded in the air-mass frame.
        return airspeed * speed_ratio * path_frame_rate

    def _finish(self, ground_velocity: Vec2, dt: float) -> None:
        self._ground_velocity = (ground_velocity[0], ground_velocity[1])
        roll = math.atan(self.lateral_acceleration / CONSTANTS_ONE_G)
        roll_limit = math.radians(self.params.fw_r_lim)
        roll = constrain(roll, -roll_limit, roll_limit)
        if dt > 0.0 and self.params.fw_l1_r_slew_max > 0.0:
            step = math.radians(self.params.fw_l1_r_slew_max) * dt
            roll = constrain(roll, self.roll_setpoint - step, self.roll_setpoint + step)
        if math.isfinite(roll):
            self.roll_setpoint = roll
