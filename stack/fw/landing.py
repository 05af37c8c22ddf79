"""Fixed-wing auto-landing: the glide slope, the flare and the approach line (PX4 v1.13
``fw_pos_control_l1/Landingslope.cpp`` and ``FixedwingPositionControl::control_auto_landing``).

Geometry (distances d to the landing point, heights relative to it): the slope at angle φ
(FW_LND_ANG) reaches the flare height h_f (FW_LND_FLALT) where the flare starts; the flare is the
exponential h(d) = H0·exp(−(L − d)/c) − H1 with H1 = FW_LND_HVIRT (a virtual height below the runway
it aims at), H0 = h_f + H1, d1 = h_f / tan φ, c = H0·d1/h_f and L = c·ln(H0/H1), so that it leaves the
slope at d = L tangent to it and touches down on the landing point. The slope is shifted back by
L − d1 so that the two meet: h_slope(d) = (d − (L − d1))·tan φ.

The landing flies the approach line from the previous waypoint through the landing point (to a point
1 km beyond, so it keeps tracking past it); it holds the line's heading with at most 10° of roll
from FW_LND_HHDIST before the landing point or once flaring. Vertically: until the slope is captured
it holds the previous waypoint's altitude; then the slope; below the flare height the flare curve,
with the pitch within FW_LND_FL_PMIN…FW_LND_FL_PMAX, and below FW_LND_TLALT the throttle at most
FW_THR_LND_MAX (PX4 v1.13). The airspeed is FW_LND_AIRSPD_SC·FW_AIRSPD_MIN throughout. Flaring, the heading
hold and the throttle limit latch until ``reset``. An idle flare (FW_THR_LND_MAX at FW_THR_IDLE) ends at the
runway's height; a flare on throttle goes on below the runway past the landing point (a vehicle still in the air
there keeps sinking instead of floating along the runway). The curve never rises again; the position controller
idles the motor once the wheels are down.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

from stack.mathlib.scalar import wrap_pi

Vec2 = tuple[float, float]

VIRTUAL_WAYPOINT_DISTANCE = 1000.0
"""How far beyond the landing point the approach line goes [m]."""
HEADING_HOLD_ROLL_LIMIT = math.radians(10.0)
"""Roll limit once the heading is held, so no wing touches the ground first."""
THROTTLE_LIMIT_FLARE_FRACTION = 0.66
"""FW_LND_TLALT < 0: the throttle limit altitude is this fraction of the flare altitude."""
THROTTLE_LIMIT_DISTANCE_MARGIN = 5.0
"""The throttle is limited only within the flare length plus this [m] of the landing point."""


class LandingSlope:
    """The glide slope and flare curve (PX4 ``Landingslope``); heights relative to the landing point."""

    def __init__(self, slope_angle: float, flare_altitude: float, h1_virtual: float) -> None:
        self.slope_angle = slope_angle
        self.flare_altitude = flare_altitude
        self.h1_virtual = h1_virtual
        self.h0 = flare_altitude + h1_virtual
        self.d1 = flare_altitude / math.tan(slope_angle)
        self.flare_constant = self.h0 * self.d1 / flare_altitude
        self.flare_length = -math.log(h1_virtual / self.h0) * self.flare_constant
        self.horizontal_slope_displacement = self.flare_length - self.d1

    def slope_altitude(self, distance: float) -> float:
        """Height of the slope at ``distance`` from the landing point [m]."""
        return (distance - self.horizontal_slope_displacement) * math.tan(self.slope_angle)

    def slope_distance(self, altitude: float) -> float:
        """Distance from the landing point where the slope is at ``altitude`` [m]."""
        return altitude / math.tan(self.slope_angle) + self.horizontal_slope_displacement

    def flare_altitude_at(self, distance: float) -> float:
        """Height of the flare curve at ``distance`` from the landing point [m] (0 at the point)."""
        return self.h0 * math.exp(-max(0.0, self.flare_length - distance) / self.flare_constant) - self.h1_virtual


@dataclass(frozen=True, slots=True)
class LandingParams:
    """The landing's settings; :meth:`from_params` takes them from the PX4 parameters."""

    slope_angle: float
    """FW_LND_ANG [rad]"""
    h1_virtual: float
    flare_altitude: float
    throttle_limit_altitude: float
    """FW_LND_TLALT, or 2/3 of FW_LND_FLALT when it is negative [m]."""
    heading_hold_distance: float
    """FW_LND_HHDIST [m], 0 = no heading hold."""
    flare_pitch_min: float
    """[rad]"""
    flare_pitch_max: float
    """[rad]"""
    airspeed: float
    """FW_LND_AIRSPD_SC·FW_AIRSPD_MIN [m/s]"""
    idle_flare: bool
    """FW_THR_LND_MAX at most FW_THR_IDLE: nothing holds the vehicle up past the landing point."""

    PARAM_NAMES = (
        "FW_LND_ANG",
        "FW_LND_HVIRT",
        "FW_LND_FLALT",
        "FW_LND_TLALT",
        "FW_LND_HHDIST",
        "FW_LND_FL_PMIN",
        "FW_LND_FL_PMAX",
        "FW_LND_AIRSPD_SC",
        "FW_AIRSPD_MIN",
        "FW_THR_LND_MAX",
        "FW_THR_IDLE",
    )

    @classmethod
    def from_params(cls, values: Mapping[str, object]) -> LandingParams:
        def f(name: str) -> float:
            return float(values[name])  # type: ignore[arg-type]

        flare_altitude = f("FW_LND_FLALT")
        throttle_limit_altitude = f("FW_LND_TLALT")
        return cls(
            slope_angle=math.radians(f("FW_LND_ANG")),
            h1_virtual=f("FW_LND_HVIRT"),
            flare_altitude=flare_altitude,
            throttle_limit_altitude=throttle_limit_altitude
            if throttle_limit_altitude > 0.0
            else THROTTLE_LIMIT_FLARE_FRACTION * flare_altitude,
            heading_hold_distance=f("FW_LND_HHDIST"),
            flare_pitch_min=math.radians(f("FW_LND_FL_PMIN")),
            flare_pitch_max=math.radians(f("FW_LND_FL_PMAX")),
            airspeed=f("FW_LND_AIRSPD_SC") * f("FW_AIRSPD_MIN"),
            idle_flare=f("FW_THR_LND_MAX") <= f("FW_THR_IDLE"),
        )


class LandingSetpoint(NamedTuple):
    altitude_sp: float
    """[m, up]"""
    airspeed_sp: float
    """Calibrated airspeed [m/s]."""
    flaring: bool
    pitch_min: float
    """Flare pitch limits [rad] while flaring; NaN: the controller's own."""
    pitch_max: float
    throttle_limited: bool
    """Below the throttle limit altitude in the flare, near the landing point: throttle at most FW_THR_LND_MAX."""
    on_slope: bool
    heading_hold: bool
    """Hold ``target_bearing`` (rudder and wheel) instead of tracking the line."""
    target_bearing: float
    """[rad]"""
    track_a: Vec2
    """The approach line to track, from A to B (B 1 km beyond the landing point)."""
    track_b: Vec2
    roll_limit: float
    """[rad], inf when the guidance's own."""


class Landing:
    """One landing: ``update`` every position-control step from the first approach step on; ``reset`` before
    the next landing (or on an abort)."""

    def __init__(self, params: LandingParams) -> None:
        self.params = params
        self.slope = LandingSlope(params.slope_angle, params.flare_altitude, params.h1_virtual)
        self.reset()

    def set_params(self, params: LandingParams) -> None:
        self.params = params
        self.slope = LandingSlope(params.slope_angle, params.flare_altitude, params.h1_virtual)

    def reset(self) -> None:
        self.flaring = False
        self.on_slope = False
        self.heading_hold = False
        self.throttle_limited = False
        self.target_bearing = math.nan
        self._flare_curve_last = math.inf

    def update(
        self,
        position: Vec2,
        altitude: float,
        land_point: Vec2,
        land_altitude: float,
        yaw: float,
        previous: Vec2 | None = None,
        previous_altitude: float = math.nan,
    ) -> LandingSetpoint:
        """Local NED (north, east) positions [m], altitudes [m, up]; ``previous`` is the waypoint before
        the landing point (None: none, and the approach line is the present bearing to the point)."""
        p = self.params
        to_land = (land_point[0] - position[0], land_point[1] - position[1])
        distance = math.hypot(to_land[0], to_land[1])
        bearing_to_land = math.atan2(to_land[1], to_land[0])
        if previous is not None:
            line = (land_point[0] - previous[0], land_point[1] - previous[1])
            line_bearing = math.atan2(line[1], line[0])
            track_a = previous
        else:
            line_bearing = bearing_to_land
            track_a = position
        track_b = (
            land_point[0] + VIRTUAL_WAYPOINT_DISTANCE * math.cos(line_bearing),
            land_point[1] + VIRTUAL_WAYPOINT_DISTANCE * math.sin(line_bearing),
        )
        # Past the landing point (it lies behind) the slope is at its height; the flare curve goes on below it.
        in_front = abs(wrap_pi(bearing_to_land - line_bearing)) < 0.5 * math.pi
        along = to_land[0] * math.cos(line_bearing) + to_land[1] * math.sin(line_bearing)

        if (
            p.heading_hold_distance > 0.0
            and not self.heading_hold
            and (distance < p.heading_hold_distance or self.flaring)
        ):
            self.heading_hold = True
            self.target_bearing = line_bearing if previous is not None else yaw

        height = altitude - land_altitude
        pitch_min = pitch_max = math.nan
        if height < p.flare_altitude or self.flaring:
            if height < p.throttle_limit_altitude and along < self.slope.flare_length + THROTTLE_LIMIT_DISTANCE_MARGIN:
                self.throttle_limited = True
            # On idle the curve ends at the runway's height (PX4 v1.13); with throttle, TECS would hold the vehicle
            # there, so the curve sinks on past the landing point (towards −FW_LND_HVIRT) until it touches down. It
            # never rises again (a vehicle that swerved away from the point).
            curve = self.slope.flare_altitude_at(along)
            flare_height = min(max(curve, 0.0) if p.idle_flare else curve, self._flare_curve_last)
            self._flare_curve_last = flare_height
            self.flaring = True
            altitude_sp = land_altitude + flare_height
            pitch_min, pitch_max = p.flare_pitch_min, p.flare_pitch_max
        else:
            slope_height = self.slope.slope_altitude(distance) if in_front else 0.0
            if height > slope_height or self.on_slope:
                self.on_slope = True
                altitude_sp = land_altitude + slope_height
            elif previous is not None and math.isfinite(previous_altitude):
                altitude_sp = previous_altitude
            else:
                altitude_sp = altitude
        return LandingSetpoint(
            altitude_sp=altitude_sp,
            airspeed_sp=p.airspeed,
            flaring=self.flaring,
            pitch_min=pitch_min,
            pitch_max=pitch_max,
            throttle_limited=self.throttle_limited,
            on_slope=self.on_slope,
            heading_hold=self.heading_hold,
            target_bearing=self.target_bearing if self.heading_hold else line_bearing,
            track_a=track_a,
            track_b=track_b,
            roll_limit=HEADING_HOLD_ROLL_LIMIT if self.heading_hold else math.inf,
        )
