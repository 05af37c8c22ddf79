"""Return mode for a multicopter: climb, fly home, descend, wait, land (PX4 navigator ``RtlDirect``).

Follows ``src/modules/navigator/rtl_direct.cpp`` and the return-altitude rule of ``rtl.cpp``:

* the return altitude is RTL_RETURN_ALT above home, lowered inside RTL_MIN_DIST of home to the height of
  the RTL_CONE_ANG cone (so a vehicle close to home does not climb high), never below twice NAV_ACC_RAD
  when outside the acceptance radius, and never below the current altitude (the vehicle never descends
  before flying home);
* phases: CLIMB to the return altitude over the current position → RETURN to above home → DESCEND to
  RTL_DESCEND_ALT above home (or stay at the return altitude if that is lower) → LOITER for RTL_LAND_DELAY
  seconds (0: no wait, −1: hold there for ever) → LAND at home → LANDED (when the land detector says so).

A phase ends when the position is within NAV_ACC_RAD horizontally and NAV_MC_ALT_RAD vertically of its
target. Positions are local NED metres; in LAND the target's z is NaN (the land controller descends).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import IntEnum
from typing import NamedTuple

from stack.commander.home import HomePosition
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class RtlParams(ParamSet):
    """The return's altitudes, cone, landing delay and acceptance radii (the catalogue's)."""

    rtl_return_alt: float
    rtl_descend_alt: float
    rtl_land_delay: float
    rtl_min_dist: float
    rtl_cone_ang: int
    nav_acc_rad: float
    nav_mc_alt_rad: float


PARAMS: tuple[Param, ...] = RtlParams.PARAMS


class RtlPhase(IntEnum):
    IDLE = 0
    CLIMB = 1
    RETURN = 2
    DESCEND = 3
    LOITER = 4
    LAND = 5
    LANDED = 6


class RtlSetpoint(NamedTuple):
    """Where return mode wants the vehicle now: local NED position (z NaN while landing) and yaw [rad]."""

    phase: RtlPhase
    position: Vec3
    yaw: float


class ReturnToLaunch:
    """``start(now_us, position, home)`` when return mode engages, then ``update(now_us, position, landed)``
    every navigation cycle."""

    __slots__ = ("_climb_xy", "_home", "_loiter_since_us", "_p", "_return_z", "phase")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.phase = RtlPhase.IDLE
        self._home = HomePosition(0.0, 0.0, 0.0, 0.0)
        self._return_z = 0.0
        self._climb_xy = (0.0, 0.0)
        self._loiter_since_us = 0
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = RtlParams.from_params(params)

    def return_altitude(self, position: Vec3, home: HomePosition) -> float:
        """Height above home [m] to fly back at, from ``position`` (PX4's cone rule)."""
        p = self._p
        distance = math.hypot(position[0] - home.x, position[1] - home.y)
        acc_rad = p.nav_acc_rad
        altitude = p.rtl_return_alt
        if distance <= acc_rad:
            altitude = 2.0 * distance
        else:
            cone = p.rtl_cone_ang
            if cone > 0.0 and distance <= p.rtl_min_dist:
                half_angle = math.radians(min(max(cone, 1.0), 89.0))
                altitude = min(altitude, distance / math.tan(half_angle))
            altitude = max(altitude, 2.0 * acc_rad)
        return max(altitude, home.z - position[2])

    def start(self, now_us: int, position: Vec3, home: HomePosition) -> RtlSetpoint:
        self._home = home
        self._return_z = home.z - self.return_altitude(position, home)
        self._climb_xy = (position[0], position[1])
        self.phase = RtlPhase.CLIMB
        return self.update(now_us, position, landed=False)

    def update(self, now_us: int, position: Vec3, landed: bool) -> RtlSetpoint:
        p = self._p
        home = self._home
        if self.phase == RtlPhase.IDLE:
            return RtlSetpoint(RtlPhase.IDLE, position, math.nan)
        if landed and self.phase in (RtlPhase.DESCEND, RtlPhase.LOITER, RtlPhase.LAND):
            self.phase = RtlPhase.LANDED
        loiter_z = max(self._return_z, home.z - p.rtl_descend_alt)
        climb_target = (self._climb_xy[0], self._climb_xy[1], self._return_z)
        if self.phase == RtlPhase.CLIMB and self._reached(position, climb_target):
            self.phase = RtlPhase.RETURN
        if self.phase == RtlPhase.RETURN and self._reached(position, (home.x, home.y, self._return_z)):
            self.phase = RtlPhase.DESCEND
        if self.phase == RtlPhase.DESCEND and self._reached(position, (home.x, home.y, loiter_z)):
            self.phase = RtlPhase.LOITER
            self._loiter_since_us = now_us
        if self.phase == RtlPhase.LOITER:
            delay = p.rtl_land_delay
            if delay >= 0.0 and now_us - self._loiter_since_us >= delay * 1e6:
                self.phase = RtlPhase.LAND

        if self.phase == RtlPhase.CLIMB:
            return RtlSetpoint(self.phase, climb_target, math.nan)
        if self.phase == RtlPhase.RETURN:
            north, east = home.x - position[0], home.y - position[1]
            heading = math.atan2(east, north) if math.hypot(north, east) > p.nav_acc_rad else math.nan
            return RtlSetpoint(self.phase, (home.x, home.y, self._return_z), heading)
        if self.phase in (RtlPhase.DESCEND, RtlPhase.LOITER):
            return RtlSetpoint(self.phase, (home.x, home.y, loiter_z), home.yaw)
        return RtlSetpoint(self.phase, (home.x, home.y, math.nan), home.yaw)

    def _reached(self, position: Vec3, target: Vec3) -> bool:
        p = self._p
        return (
            math.hypot(position[0] - target[0], position[1] - target[1]) <= p.nav_acc_rad
            and abs(position[2] - target[2]) <= p.nav_mc_alt_rad
        )
