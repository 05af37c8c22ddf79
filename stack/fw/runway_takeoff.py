"""Runway takeoff for planes on wheels (PX4 v1.13 ``fw_pos_control_l1/runway_takeoff/RunwayTakeoff.cpp``).

The ground roll and climb-out as a sequence of states, each deciding what the position controller
flies:

1. THROTTLE_RAMP: throttle ramps from 0 to RWTO_MAX_THR over RWTO_RAMP_TIME (or until 90 % of the
   rotation airspeed); wings level, pitch RWTO_PSP, heading held with the wheel.
2. CLAMPED_TO_RUNWAY: RWTO_MAX_THR, the same attitude, until the airspeed reaches
   RWTO_AIRSPD_SCL·FW_AIRSPD_MIN.
3. TAKEOFF: rotation: TECS' pitch (at most RWTO_MAX_PITCH), climb-out throttle, wings level and the
   heading still held until RWTO_NAV_ALT above the runway.
4. CLIMBOUT: navigation, roll within RWTO_MAX_ROLL, until FW_CLMBOUT_DIFF above the runway.
5. FLY: the normal limits.

The heading held on the ground (RWTO_HDG) is the airframe's at the start (0) or the navigation's, to
the takeoff waypoint (1). Plain class: the caller passes time (µs) and state.
"""

from __future__ import annotations

import math
from enum import IntEnum

from stack.mathlib.scalar import constrain
from stack.params.binding import ParamSet

Vec2 = tuple[float, float]

RAMP_AIRSPEED_RATIO = 0.9
"""The ramp ends early at this fraction of the rotation airspeed."""
MAX_PITCH_USED = math.radians(0.1)
"""RWTO_MAX_PITCH at or below this means "use FW_P_LIM_MAX" (PX4: > 0.1°)."""


class RunwayTakeoffState(IntEnum):
    THROTTLE_RAMP = 0
    CLAMPED_TO_RUNWAY = 1
    TAKEOFF = 2
    CLIMBOUT = 3
    FLY = 4


class RunwayTakeoffParams(ParamSet):
    """The runway takeoff's settings (the catalogue's RWTO_*, FW_AIRSPD_MIN and FW_CLMBOUT_DIFF). RWTO_HDG: 0 the
    airframe heading at the start, 1 the navigation's (to the takeoff waypoint); RWTO_NAV_ALT and FW_CLMBOUT_DIFF
    are heights above the runway."""

    rwto_hdg: int
    rwto_nav_alt: float
    rwto_max_thr: float
    rwto_psp: float
    rwto_max_pitch: float
    rwto_max_roll: float
    rwto_airspd_scl: float
    rwto_ramp_time: float
    fw_airspd_min: float
    fw_clmbout_diff: float

class RunwayTakeoff:
    """PX4's runway takeoff state machine. ``init`` on the runway, ``update`` every step, then take the
    setpoints through ``throttle``, ``pitch``, ``roll``, ``yaw`` and the limits through ``min_pitch``,
    ``max_pitch``; ``wheel_steering`` says the heading is held on the ground (rudder and wheel)."""

    def __init__(self, params: RunwayTakeoffParams) -> None:
        self.params = params
        self.state = RunwayTakeoffState.THROTTLE_RAMP
        self.initialized = False
        self.climbout = False
        self.start_position: Vec2 = (math.nan, math.nan)
        self.initial_yaw = 0.0
        self._start_us = 0

    def set_params(self, params: RunwayTakeoffParams) -> None:
        self.params = params

    def init(self, time_us: int, yaw: float, position: Vec2) -> None:
        """Start on the runway: the heading to hold (RWTO_HDG 0) and where the roll starts."""
        self.initial_yaw = yaw
        self.initialized = True
        self.state = RunwayTakeoffState.THROTTLE_RAMP
        self._start_us = time_us
        self.climbout = True
        self.start_position = (position[0], position[1])

    def reset(self) -> None:
        self.initialized = False
        self.state = RunwayTakeoffState.THROTTLE_RAMP

    def update(self, time_us: int, airspeed: float, altitude_agl: float, position: Vec2) -> RunwayTakeoffState:
        """Advance with the (calibrated) ``airspeed`` [m/s] and the height above the runway [m]."""
        p = self.params
        rotation_airspeed = p.rwto_airspd_scl * p.fw_airspd_min
        s = RunwayTakeoffState
        if self.state == s.THROTTLE_RAMP:
            if self._elapsed(time_us) > p.rwto_ramp_time or airspeed > rotation_airspeed * RAMP_AIRSPEED_RATIO:
                self.state = s.CLAMPED_TO_RUNWAY
        elif self.state == s.CLAMPED_TO_RUNWAY:
            if airspeed > rotation_airspeed:
                self.state = s.TAKEOFF
        elif self.state == s.TAKEOFF:
            if altitude_agl > p.rwto_nav_alt:
                self.state = s.CLIMBOUT
                if p.rwto_hdg == 0:
                    # Navigation to the takeoff waypoint starts from here.
                    self.start_position = (position[0], position[1])
        elif self.state == s.CLIMBOUT and altitude_agl > p.fw_clmbout_diff:
            self.climbout = False
            self.state = s.FLY
        return self.state

    @property
    def wheel_steering(self) -> bool:
        """The heading is held directly (rudder and nose wheel) until navigation starts."""
        return self.state < RunwayTakeoffState.CLIMBOUT

    @property
    def reset_integrators(self) -> bool:
        """On the runway the attitude integrators must not wind up."""
        return self.state < RunwayTakeoffState.TAKEOFF

    def throttle(self, time_us: int, tecs_throttle: float) -> float:
        p = self.params
        if self.state == RunwayTakeoffState.THROTTLE_RAMP:
            ramp = self._elapsed(time_us) / p.rwto_ramp_time if p.rwto_ramp_time > 0.0 else 1.0
            return min(ramp * p.rwto_max_thr, p.rwto_max_thr)
        if self.state == RunwayTakeoffState.CLAMPED_TO_RUNWAY:
            return p.rwto_max_thr
        return tecs_throttle

    def pitch(self, tecs_pitch: float) -> float:
        if self.state <= RunwayTakeoffState.CLAMPED_TO_RUNWAY:
            return math.radians(self.params.rwto_psp)
        return tecs_pitch

    def roll(self, nav_roll: float) -> float:
        if self.state < RunwayTakeoffState.CLIMBOUT:
            return 0.0
        if self.state < RunwayTakeoffState.FLY:
            max_roll = math.radians(self.params.rwto_max_roll)
            return constrain(nav_roll, -max_roll, max_roll)
        return nav_roll

    def yaw(self, nav_yaw: float) -> float:
        if self.params.rwto_hdg == 0 and self.state < RunwayTakeoffState.CLIMBOUT:
            return self.initial_yaw
        return nav_yaw

    def min_pitch(self, climbout_min: float, pitch_min: float) -> float:
        """TECS' lower pitch limit: the climb-out minimum until FLY."""
        return climbout_min if self.state < RunwayTakeoffState.FLY else pitch_min

    def max_pitch(self, pitch_max: float) -> float:
        """TECS' upper pitch limit: RWTO_MAX_PITCH (when set) until FLY."""
        max_pitch = math.radians(self.params.rwto_max_pitch)
        if self.state < RunwayTakeoffState.FLY and max_pitch > MAX_PITCH_USED:
            return max_pitch
        return pitch_max

    def _elapsed(self, time_us: int) -> float:
        return (time_us - self._start_us) * 1e-6
