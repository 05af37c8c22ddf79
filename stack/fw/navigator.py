"""The fixed-wing navigator: the mode and the mission turned into a position-setpoint triplet (PX4 navigator).

PX4's navigator publishes ``position_setpoint_triplet`` (previous, current, next) and the fixed-wing position
controller flies it: lines between waypoints, loiter circles, the takeoff and the landing. Here, per
``vehicle_status.nav_state``:

* Takeoff: a TAKEOFF setpoint far ahead on the runway (``RUNWAY_AHEAD`` along the heading at the start), at
  the takeoff altitude above home; the previous setpoint is the runway start, so the climb-out tracks the
  runway's line. The runway (start and heading) is remembered for the landing.
* Hold: a loiter circle of NAV_LOITER_RAD about where the vehicle was when Hold began (PX4's "loiter at the
  current position"), at that altitude (after a takeoff, at the takeoff altitude), or about a go-to target
  (``navigation_request``).
* Mission: the uploaded items through :class:`~stack.mission.tracker.MissionTracker` (fixed-wing acceptance:
  the guidance's switching distance, NAV_FW_ALT_RAD, loiter items reached on their circle); waypoints are
  POSITION setpoints with the leg's start as ``previous`` and the following waypoint as ``next``; loiter items
  are LOITER setpoints; a landing item lands along the line from the previous waypoint.
* Return: fly home at RTL_RETURN_ALT (or higher if already higher), circle home down to RTL_DESCEND_ALT, then
  land on the runway it took off from.
* Land: circle down where the vehicle is to RTL_DESCEND_ALT if higher, then land on the runway.

A landing (:class:`LandingApproach`) flies to an entry point on the runway's extended centre line, far enough
back to be established on the line before the glide slope (FW_LND_ANG) starts, then a LAND setpoint at the
touchdown point with the entry point as ``previous``: fw_pos_control follows the slope and flares.

Positions are local NED metres. The output is None when the mode flies without a triplet (manual modes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import IntEnum
from typing import NamedTuple

from stack.commander.home import HomePosition
from stack.fw.runway import Runway
from stack.mathlib.vector import Vec3
from stack.mission import feasibility, tracker
from stack.mission.items import LOITER_COMMANDS, MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_WAYPOINT
from stack.mission.store import MissionStore
from stack.msg.fixedwing import PositionSetpoint, PositionSetpointTriplet
from stack.msg.navigation import NavigationRequest
from stack.msg.system import VehicleStatus
from stack.params.binding import ParamSet, combine
from stack.params.param import Param

NS = VehicleStatus
SP = PositionSetpoint
NAN = math.nan

RUNWAY_AHEAD = 2000.0
"""How far ahead of the runway start the takeoff setpoint lies [m]: the climb-out holds the runway's line."""
APPROACH_STRAIGHT_LOITERS = 2.0
"""The straight before the glide slope, in loiter radii: room to settle on the centre line after the turn."""
LOITER_ALTITUDE_REACHED = 2.0
"""How close to its altitude a descending loiter must be [m] before the landing approach starts."""

class FwNavigatorParams(ParamSet):
    """What the navigator reads itself (the mission's tracker and feasibility check take theirs from the same
    values)."""

    nav_loiter_rad: float
    mis_takeoff_alt: float
    rtl_return_alt: float
    rtl_descend_alt: float
    fw_lnd_ang: float
    nav_acc_rad: float
    nav_fw_alt_rad: float


PARAMS: tuple[Param, ...] = combine(FwNavigatorParams.PARAMS, tracker.PARAMS, feasibility.PARAMS)


class LandPhase(IntEnum):
    RETURN = 0
    LOITER_DOWN = 1
    APPROACH = 2
    LAND = 3


class FwNavigatorInputs(NamedTuple):
    now_us: int
    nav_state: int
    armed: bool
    landed: bool
    position: Vec3
    """Local NED; NaN components when not known."""
    yaw: float
    home: HomePosition | None
    request: NavigationRequest | None
    acceptance_radius: float
    """The guidance's waypoint switching distance (``position_controller_status``); NaN: none."""


def _setpoint(kind: int, point: Vec3, **fields: float | bool) -> PositionSetpoint:
    return PositionSetpoint(valid=True, type=kind, x=point[0], y=point[1], z=point[2], **fields)


def _finite(v: Vec3) -> bool:
    return all(math.isfinite(c) for c in v)


class LandingApproach(NamedTuple):
    """The geometry of a landing: touchdown point, direction, approach height and the entry point."""

    touchdown: Vec3
    heading: float
    height: float
    entry: Vec3

    @classmethod
    def build(cls, touchdown: Vec3, heading: float, height: float, slope_deg: float, straight: float):
        slope = math.tan(math.radians(max(slope_deg, 0.5)))
        back = height / slope + straight
        c, s = math.cos(heading), math.sin(heading)
        entry = (touchdown[0] - back * c, touchdown[1] - back * s, touchdown[2] - height)
        return cls(touchdown, heading, height, entry)

    def setpoints(self, phase: LandPhase, position: Vec3) -> tuple[PositionSetpoint, PositionSetpoint]:
        """(previous, current) for the APPROACH or LAND phase."""
        if phase == LandPhase.APPROACH:
            return _setpoint(SP.SETPOINT_TYPE_POSITION, position), _setpoint(SP.SETPOINT_TYPE_POSITION, self.entry)
        return _setpoint(SP.SETPOINT_TYPE_POSITION, self.entry), _setpoint(
            SP.SETPOINT_TYPE_LAND, self.touchdown, yaw=self.heading
        )


class FixedwingNavigator:
    """``missions`` holds the uploaded mission; ``update(inputs)`` every cycle returns the triplet."""

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._p = FwNavigatorParams()
        self._values: dict[str, object] = {}
        """The values given so far, by PX4 name (a later ``set_params`` may give only some)."""
        self.missions = MissionStore(fixed_wing=True, on_replaced=self._mission_replaced)
        self.runway: Runway | None = None
        self._active: int | None = None
        self._reposition_counter = 0
        self._mission_start_counter = 0
        self._loiter_center: Vec3 = (NAN, NAN, NAN)
        self._land_phase = LandPhase.RETURN
        self._landing: LandingApproach | None = None
        self._return_altitude = NAN
        self._mission_returning = False
        self._takeoff: tuple[Vec3, Vec3] | None = None
        self._return_from: Vec3 = (NAN, NAN, NAN)
        self._approach_from: Vec3 = (NAN, NAN, NAN)
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._values.update(params)
        self._p = FwNavigatorParams.from_params(self._values)
        self.missions.set_params(self._values)

    @property
    def loiter_radius(self) -> float:
        return self._p.nav_loiter_rad

    # ------------------------------------------------------------------ cycle

    def update(self, inp: FwNavigatorInputs) -> PositionSetpointTriplet | None:
        if not inp.armed:
            self._active = None
            return None
        if not _finite(inp.position):
            return None  # fw_pos_control flies its own descent without a position
        if inp.nav_state != self._active:
            self._activate(inp, self._active)
            self._active = inp.nav_state
        nav = inp.nav_state
        if nav == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
            return self._fly_takeoff()
        if nav == NS.NAVIGATION_STATE_AUTO_LOITER:
            self._take_reposition(inp)
            return self._loiter(self._loiter_center)
        if nav == NS.NAVIGATION_STATE_AUTO_MISSION:
            return self._mission(inp)
        if nav in (NS.NAVIGATION_STATE_AUTO_RTL, NS.NAVIGATION_STATE_AUTO_LAND):
            return self._land(inp)
        return None

    def _activate(self, inp: FwNavigatorInputs, previous: int | None) -> None:
        nav = inp.nav_state
        position = inp.position
        if nav == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
            self._start_takeoff(inp, self._takeoff_altitude(inp))
        elif nav == NS.NAVIGATION_STATE_AUTO_LOITER:
            self._loiter_center = position
            if previous == NS.NAVIGATION_STATE_AUTO_TAKEOFF and self._takeoff is not None:
                # Hold after a takeoff circles at the takeoff altitude, which the climb has not quite reached.
                self._loiter_center = (position[0], position[1], self._takeoff[1][2])
        elif nav == NS.NAVIGATION_STATE_AUTO_MISSION:
            self._start_mission(inp)
        elif nav == NS.NAVIGATION_STATE_AUTO_RTL:
            self._start_return(inp)
        elif nav == NS.NAVIGATION_STATE_AUTO_LAND:
            self._start_land(inp)

    # ------------------------------------------------------------------ takeoff and hold

    def _takeoff_altitude(self, inp: FwNavigatorInputs) -> float:
        altitude = inp.request.takeoff_altitude if inp.request is not None else NAN
        return altitude if math.isfinite(altitude) and altitude > 0.0 else self._p.mis_takeoff_alt

    def _ground_z(self, inp: FwNavigatorInputs) -> float:
        return inp.home.z if inp.home is not None else inp.position[2]

    def _start_takeoff(self, inp: FwNavigatorInputs, altitude: float, towards: Vec3 | None = None) -> None:
        start = inp.position
        heading = inp.yaw if math.isfinite(inp.yaw) else 0.0
        if towards is not None and math.hypot(towards[0] - start[0], towards[1] - start[1]) > self._p.nav_acc_rad:
            target = towards
        else:
            target = (
                start[0] + RUNWAY_AHEAD * math.cos(heading),
                start[1] + RUNWAY_AHEAD * math.sin(heading),
                self._ground_z(inp) - altitude,
            )
        if self.runway is None or inp.landed:
            self.runway = Runway(start, heading)
        self._takeoff = (start, target)

    def _fly_takeoff(self) -> PositionSetpointTriplet | None:
        if self._takeoff is None:
            return None
        start, target = self._takeoff
        return PositionSetpointTriplet(
            previous=_setpoint(SP.SETPOINT_TYPE_POSITION, start),
            current=_setpoint(SP.SETPOINT_TYPE_TAKEOFF, target),
        )

    def _take_reposition(self, inp: FwNavigatorInputs) -> None:
        request = inp.request
        if request is None or request.reposition_counter == self._reposition_counter:
            return
        self._reposition_counter = request.reposition_counter
        self._loiter_center = tuple(  # type: ignore[assignment]
            t if math.isfinite(t) else p for t, p in zip(request.reposition, inp.position, strict=True)
        )

    def _loiter(self, center: Vec3, radius: float = NAN, previous: PositionSetpoint | None = None):
        radius = radius if math.isfinite(radius) else self.loiter_radius
        current = _setpoint(
            SP.SETPOINT_TYPE_LOITER,
            center,
            loiter_radius=abs(radius),
            loiter_direction_counter_clockwise=radius < 0.0,
        )
        return PositionSetpointTriplet(previous=previous or PositionSetpoint(), current=current)

    # ------------------------------------------------------------------ mission

    def _mission_replaced(self) -> None:
        self._mission_returning = False
        if self._active == NS.NAVIGATION_STATE_AUTO_MISSION:
            self._active = None  # start the new mission on the next update

    def _start_mission(self, inp: FwNavigatorInputs) -> None:
        tracker = self.missions.tracker
        self._mission_returning = False
        if tracker is None:
            self._loiter_center = inp.position
            return
        first = -1
        request = inp.request
        if request is not None and request.mission_start_counter != self._mission_start_counter:
            self._mission_start_counter = request.mission_start_counter
            if request.mission_start_index < tracker.progress.seq_total:
                first = request.mission_start_index
        progress = self.missions.start(inp.now_us, inp.position, first, inp.home)
        self._on_item(inp, progress.seq_current)

    def _on_item(self, inp: FwNavigatorInputs, seq: int) -> None:
        """Set up what a new current item needs: a takeoff's runway, a landing's approach."""
        mission = self.missions.mission
        tracker = self.missions.tracker
        if mission is None or tracker is None:
            return
        item = mission[seq]
        target = tracker.progress.target
        if item.command == MAV_CMD_NAV_TAKEOFF:
            altitude = self._ground_z(inp) - target[2]
            self._start_takeoff(inp, altitude, towards=target)
        elif item.command == MAV_CMD_NAV_LAND:
            previous = tracker.progress.previous
            touchdown = (target[0], target[1], self._ground_z(inp))
            heading = math.atan2(touchdown[1] - previous[1], touchdown[0] - previous[0])
            self._landing = self._approach(touchdown, heading, inp)
            self._land_phase = LandPhase.APPROACH
            self._approach_from = inp.position

    def _mission(self, inp: FwNavigatorInputs) -> PositionSetpointTriplet:
        tracker, mission = self.missions.tracker, self.missions.mission
        if self._mission_returning:
            return self._land(inp)
        if tracker is None or mission is None:
            return self._loiter(self._loiter_center)
        seq_before = tracker.progress.seq_current
        progress = tracker.update(inp.now_us, inp.position, inp.yaw, inp.landed, inp.acceptance_radius)
        if progress.return_requested:
            self._mission_returning = True
            self._start_return(inp)
            return self._land(inp)
        if progress.seq_current != seq_before:
            self._on_item(inp, progress.seq_current)
        item = mission[progress.seq_current]
        speed = progress.cruise_speed
        if progress.finished and item.command != MAV_CMD_NAV_LAND:
            return self._loiter(progress.target)
        if item.command == MAV_CMD_NAV_TAKEOFF:
            return self._fly_takeoff() or self._loiter(progress.target)
        if item.command == MAV_CMD_NAV_LAND:
            return self._land(inp)
        previous = _setpoint(SP.SETPOINT_TYPE_POSITION, progress.previous)
        if item.command in LOITER_COMMANDS:
            return self._loiter(progress.target, tracker.loiter_radius(item), previous)
        current = _setpoint(
            SP.SETPOINT_TYPE_POSITION,
            progress.target,
            acceptance_radius=item.acceptance_radius if item.acceptance_radius > 0.0 else NAN,
            cruising_speed=speed,
        )
        return PositionSetpointTriplet(previous=previous, current=current, next=self._next(progress.seq_current, inp))

    def _next(self, seq: int, inp: FwNavigatorInputs) -> PositionSetpoint:
        """The following waypoint, so the guidance can turn onto the next leg before reaching this one."""
        mission = self.missions.mission
        if mission is None or mission[seq].command != MAV_CMD_NAV_WAYPOINT or not mission[seq].autocontinue:
            return PositionSetpoint()
        hx, hy, hz = inp.home.position if inp.home is not None else (0.0, 0.0, 0.0)
        for item in mission.items[seq + 1 :]:
            if not item.has_position:
                continue
            if item.command != MAV_CMD_NAV_WAYPOINT or not _finite(item.position):
                return PositionSetpoint()
            return _setpoint(SP.SETPOINT_TYPE_POSITION, (hx + item.north, hy + item.east, hz + item.down))
        return PositionSetpoint()

    # ------------------------------------------------------------------ return and land

    def _approach(self, touchdown: Vec3, heading: float, inp: FwNavigatorInputs) -> LandingApproach:
        height = max(self._p.rtl_descend_alt, 1.0)
        straight = APPROACH_STRAIGHT_LOITERS * self.loiter_radius
        return LandingApproach.build(touchdown, heading, height, self._p.fw_lnd_ang, straight)

    def _home_runway(self, inp: FwNavigatorInputs) -> tuple[Vec3, float]:
        """The touchdown point and direction of a landing at home: the takeoff's runway when known."""
        if inp.home is not None:
            ground = (inp.home.x, inp.home.y, inp.home.z)
            heading = self.runway.heading if self.runway is not None else inp.home.yaw
        else:
            ground = (inp.position[0], inp.position[1], inp.position[2])
            heading = self.runway.heading if self.runway is not None else inp.yaw
        if self.runway is not None:
            ground = (self.runway.start[0], self.runway.start[1], ground[2])
        return ground, heading if math.isfinite(heading) else 0.0

    def _start_return(self, inp: FwNavigatorInputs) -> None:
        touchdown, heading = self._home_runway(inp)
        self._landing = self._approach(touchdown, heading, inp)
        ground = touchdown[2]
        self._return_altitude = min(inp.position[2], ground - self._p.rtl_return_alt)
        self._loiter_center = (touchdown[0], touchdown[1], self._return_altitude)
        self._land_phase = LandPhase.RETURN
        self._return_from = inp.position

    def _start_land(self, inp: FwNavigatorInputs) -> None:
        touchdown, heading = self._home_runway(inp)
        self._landing = self._approach(touchdown, heading, inp)
        self._loiter_center = inp.position
        self._land_phase = LandPhase.LOITER_DOWN
        self._approach_from = inp.position

    def _land(self, inp: FwNavigatorInputs) -> PositionSetpointTriplet:
        landing = self._landing
        if landing is None:
            return self._loiter(inp.position)
        position = inp.position
        p = self._p
        if self._land_phase == LandPhase.RETURN:
            center = self._loiter_center
            if math.hypot(center[0] - position[0], center[1] - position[1]) <= self.loiter_radius:
                self._land_phase = LandPhase.LOITER_DOWN
            else:
                return PositionSetpointTriplet(
                    previous=_setpoint(SP.SETPOINT_TYPE_POSITION, self._return_from),
                    current=_setpoint(SP.SETPOINT_TYPE_POSITION, center),
                )
        if self._land_phase == LandPhase.LOITER_DOWN:
            center = (self._loiter_center[0], self._loiter_center[1], landing.entry[2])
            if abs(position[2] - center[2]) <= LOITER_ALTITUDE_REACHED:
                self._land_phase = LandPhase.APPROACH
                self._approach_from = position
            else:
                return self._loiter(center)
        if self._land_phase == LandPhase.APPROACH:
            entry = landing.entry
            radius = inp.acceptance_radius if inp.acceptance_radius > 0.0 else p.nav_acc_rad
            if math.hypot(entry[0] - position[0], entry[1] - position[1]) <= max(radius, p.nav_acc_rad):
                self._land_phase = LandPhase.LAND
            else:
                previous, current = landing.setpoints(LandPhase.APPROACH, self._approach_from)
                return PositionSetpointTriplet(previous=previous, current=current)
        previous, current = landing.setpoints(LandPhase.LAND, position)
        return PositionSetpointTriplet(previous=previous, current=current)
