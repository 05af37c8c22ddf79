"""Fixed-wing auto-landing: the glide slope, the flare and the approach line (PX4 v1.14
``src/modules/fw_pos_control/FixedwingPositionControl.cpp``, ``control_auto_landing_straight``).

Vertically (heights relative to the landing point, d the distance to it): the glide slope is the straight line
h(d) = d·tan(FW_LND_ANG) through the landing point, capped at the approach entrance's height (the previous
waypoint's, or the vehicle's when the landing began without one). Until the vehicle is at or above the slope it
holds the entrance's height; from then on (latched) it follows the slope. (PX4 v1.14 holds the present altitude
below the slope, which leaves a sink below it uncorrected, and never latches; this is v1.13's capture.) Past the
landing point (d < 0 along the approach line) the slope goes on below the runway; the flare takes over before.

The flare starts below the higher of FW_LND_FLALT and FW_LND_FL_TIME·(sink rate), and latches until ``reset``.
From its start it commands a height rate instead of an altitude: over FW_LND_FL_TIME seconds, with the ramp
r = √(t/FW_LND_FL_TIME), the height-rate setpoint goes from the vertical speed at the flare's start to
−FW_LND_FL_SINK, the pitch limits from FW_P_LIM_MIN…FW_P_LIM_MAX to FW_LND_FL_PMIN…FW_LND_FL_PMAX and the
largest throttle from FW_THR_MAX to FW_THR_IDLE (the least throttle is FW_THR_IDLE throughout). The throttle sent
is blended linearly over the same time from the throttle at the flare's start to TECS' (:meth:`Landing.flare_throttle`).
With FW_LND_TD_TIME > 0, from max(FW_LND_TD_TIME, FW_LND_FL_TIME) after the flare's start both pitch limits go to
RWTO_PSP within 0.5 s, to put the nose wheel down. The airspeed is FW_LND_AIRSPD_SC·FW_AIRSPD_MIN throughout.

Laterally: the approach line from the previous waypoint through the landing point (to a point 1 km beyond, so it
keeps tracking past it); its heading is held with at most 10° of roll from FW_LND_HHDIST before the landing point
or once flaring (PX4 v1.13's heading hold; v1.14 tracks the line down to the runway instead).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.scalar import constrain
from stack.params.binding import ParamSet

Vec2 = tuple[float, float]

VIRTUAL_WAYPOINT_DISTANCE = 1000.0
"""How far beyond the landing point the approach line goes [m]."""
HEADING_HOLD_ROLL_LIMIT = math.radians(10.0)
"""Roll limit once the heading is held, so no wing touches the ground first."""
POST_TOUCHDOWN_CLAMP_TIME = 0.5
"""Time over which the pitch limits go to RWTO_PSP at the touchdown time [s] (PX4's constant)."""


class LandingParams(ParamSet):
    """The landing's settings (the catalogue's FW_LND_*, with the pitch and throttle limits the flare starts from).
    FW_LND_TD_TIME counts from the flare's start (≤ 0: no nose-down clamp); FW_LND_HHDIST 0: no heading hold;
    RWTO_PSP is the pitch on the wheels the touchdown clamp goes to (PX4 v1.14 blends the parameter's degrees
    into its radian limits unconverted; here it is converted)."""

    fw_lnd_ang: float
    fw_lnd_flalt: float
    fw_lnd_fl_time: float
    fw_lnd_fl_sink: float
    fw_lnd_td_time: float
    fw_lnd_hhdist: float
    fw_lnd_fl_pmin: float
    fw_lnd_fl_pmax: float
    fw_lnd_airspd_sc: float
    fw_airspd_min: float
    fw_p_lim_min: float
    fw_p_lim_max: float
    rwto_psp: float
    fw_thr_max: float
    fw_thr_idle: float

class LandingSetpoint(NamedTuple):
    altitude_sp: float
    """[m, up]; NaN while flaring: the height rate alone is controlled."""
    height_rate_sp: float
    """[m/s, up] while flaring; NaN before."""
    airspeed_sp: float
    """Calibrated airspeed [m/s]."""
    flaring: bool
    pitch_min: float
    """Pitch limits [rad] while flaring; NaN: the controller's own."""
    pitch_max: float
    throttle_min: float
    """Throttle limits while flaring; NaN: the controller's own."""
    throttle_max: float
    on_slope: bool
    """The glide slope is captured (latched until ``reset``)."""
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
        self.reset()

    def set_params(self, params: LandingParams) -> None:
        self.params = params

    def reset(self) -> None:
        self.flaring = False
        self.on_slope = False
        self.heading_hold = False
        self.target_bearing = math.nan
        self.entrance_height = math.nan
        self.flare_start = math.nan
        self.flare_initial_height_rate = math.nan
        self.flare_initial_throttle = math.nan
        self.flare_ramp = 0.0  # time since the flare's start over FW_LND_FL_TIME, within [0, 1]

    def update(
        self,
        position: Vec2,
        altitude: float,
        land_point: Vec2,
        land_altitude: float,
        yaw: float,
        previous: Vec2 | None = None,
        previous_altitude: float = math.nan,
        *,
        now: float,
        down_speed: float,
        throttle: float = math.nan,
    ) -> LandingSetpoint:
        """Local NED (north, east) positions [m], altitudes [m, up]; ``previous`` is the waypoint before the
        landing point (None: none, and the approach line is the present bearing to the point). ``now`` [s],
        ``down_speed`` the vertical speed [m/s, NED down], ``throttle`` the one commanded last step (held from
        the flare's start for :meth:`flare_throttle`)."""
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
        # The slope is flown by the distance to the landing point (PX4 v1.13's; v1.14 takes it along the approach
        # line): a vehicle still turning onto the line, abeam of the point, is not yet low on the slope. Past the
        # point it goes on below the runway.
        along = to_land[0] * math.cos(line_bearing) + to_land[1] * math.sin(line_bearing)
        slope_distance = distance if along > 0.0 else along
        height = altitude - land_altitude
        if not math.isfinite(self.entrance_height):
            entrance = previous_altitude if previous is not None and math.isfinite(previous_altitude) else altitude
            self.entrance_height = max(entrance - land_altitude, 0.0)

        if (
            p.fw_lnd_hhdist > 0.0
            and not self.heading_hold
            and (distance < p.fw_lnd_hhdist or self.flaring)
        ):
            self.heading_hold = True
            self.target_bearing = line_bearing if previous is not None else yaw

        sink = down_speed if math.isfinite(down_speed) else 0.0
        flare_height = max(p.fw_lnd_fl_time * sink, p.fw_lnd_flalt)
        slope_height = min(slope_distance * math.tan(math.radians(p.fw_lnd_ang)), self.entrance_height)
        altitude_sp = height_rate_sp = pitch_min = pitch_max = throttle_min = throttle_max = math.nan
        if height < flare_height or self.flaring:
            if not self.flaring:
                self.flaring = True
                self.flare_start = now
                self.flare_initial_height_rate = -sink
                self.flare_initial_throttle = throttle
            elapsed = now - self.flare_start
            self.flare_ramp = constrain(elapsed / max(p.fw_lnd_fl_time, 1e-3), 0.0, 1.0)
            # PX4 eases the setpoints in on the square root of the ramp: most of the change comes early.
            r = math.sqrt(self.flare_ramp)
            height_rate_sp = r * -p.fw_lnd_fl_sink + (1.0 - r) * self.flare_initial_height_rate
            pitch_min = r * math.radians(p.fw_lnd_fl_pmin) + (1.0 - r) * math.radians(p.fw_p_lim_min)
            pitch_max = r * math.radians(p.fw_lnd_fl_pmax) + (1.0 - r) * math.radians(p.fw_p_lim_max)
            if p.fw_lnd_td_time > 0.0:
                touchdown = max(p.fw_lnd_td_time, p.fw_lnd_fl_time)
                clamp = constrain((elapsed - touchdown) / POST_TOUCHDOWN_CLAMP_TIME, 0.0, 1.0)
                runway_pitch = math.radians(p.rwto_psp)
                pitch_min = clamp * runway_pitch + (1.0 - clamp) * pitch_min
                pitch_max = clamp * runway_pitch + (1.0 - clamp) * pitch_max
            throttle_min = p.fw_thr_idle
            throttle_max = r * p.fw_thr_idle + (1.0 - r) * p.fw_thr_max
        elif height >= slope_height or self.on_slope:
            self.on_slope = True
            altitude_sp = land_altitude + slope_height
        else:
            altitude_sp = land_altitude + self.entrance_height
        return LandingSetpoint(
            altitude_sp=altitude_sp,
            height_rate_sp=height_rate_sp,
            airspeed_sp=p.fw_lnd_airspd_sc * p.fw_airspd_min,
            flaring=self.flaring,
            pitch_min=pitch_min,
            pitch_max=pitch_max,
            throttle_min=throttle_min,
            throttle_max=throttle_max,
            on_slope=self.on_slope,
            heading_hold=self.heading_hold,
            target_bearing=self.target_bearing if self.heading_hold else line_bearing,
            track_a=track_a,
            track_b=track_b,
            roll_limit=HEADING_HOLD_ROLL_LIMIT if self.heading_hold else math.inf,
        )

    def flare_throttle(self, tecs_throttle: float) -> float:
        """The throttle to send while flaring: from the throttle at the flare's start to TECS' over
        FW_LND_FL_TIME (PX4 keeps the throttle continuous where altitude control hands over to height rate)."""
        if not math.isfinite(self.flare_initial_throttle):
            return tecs_throttle
        return self.flare_ramp * tecs_throttle + (1.0 - self.flare_ramp) * self.flare_initial_throttle
