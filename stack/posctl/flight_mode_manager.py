"""The flight-mode manager: the current mode turned into a trajectory setpoint (PX4 navigator + FlightModeManager).

PX4 splits this between the navigator (mission, return, takeoff and land logic producing waypoints) and
the flight-mode manager's flight tasks (jerk-limited trajectories through them). Here one class does both,
per ``vehicle_status.nav_state``:

* Takeoff: climb straight up at MPC_TKO_SPEED while the position controller ramps its thrust (a
  velocity setpoint, PX4's "want takeoff"), then a smooth trajectory to the takeoff altitude above home.
* Hold: brake to the stopping point and hold it; a go-to (``navigation_request``) flies a smooth
  trajectory to its target at the requested or cruise speed.
* Mission: the uploaded mission's items through :class:`~stack.mission.tracker.MissionTracker`,
  waypoint to waypoint through :class:`~stack.posctl.position_smoothing.PositionSmoothing` (turning
  onto the next leg within the acceptance radius, stopping where an item holds or ends).
* Return: :class:`~stack.commander.rtl.ReturnToLaunch`'s phases (climb, return, descend, loiter), then land.
* Land: hold the landing point horizontally and descend at MPC_Z_V_AUTO_DN above MPC_LAND_ALT1, slowing
  to MPC_LAND_SPEED below MPC_LAND_ALT2 (heights above home), with the descent rate slewed at
  MPC_ACC_DOWN_MAX. Descend (no position estimate): level, descending at MPC_LAND_SPEED.
* Position and Altitude: the pilot's sticks (:mod:`stack.posctl.manual_tasks`).

Headings in the auto modes follow the item's or request's yaw; otherwise MPC_YAW_MODE (0 toward the
waypoint, 1 toward home, 2 away from home, 3 along the trajectory, 4 hold) on mission legs and the
return leg, and the current heading elsewhere; the heading setpoint turns at most MPC_YAWRAUTO_MAX.
Other modes (manual, stabilized, acro, offboard...) produce no setpoint.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import NamedTuple

from stack.commander import rtl
from stack.commander.home import HomePosition
from stack.commander.rtl import ReturnToLaunch, RtlPhase
from stack.mathlib.scalar import interpolate
from stack.mathlib.vector import Vec3
from stack.mission import feasibility, tracker
from stack.mission.items import MAV_CMD_NAV_LAND, MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_WAYPOINT, Mission
from stack.mission.store import MissionStatus, MissionStore
from stack.mission.tracker import MissionTracker
from stack.msg.navigation import NavigationRequest
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus
from stack.params.binding import ParamSet, combine
from stack.params.param import Param
from stack.posctl.flight_task import NAN, TrajectoryCommand, VehicleState, YawSlew, stopping_point
from stack.posctl.manual_tasks import ManualAltitudeTask, ManualPositionTask
from stack.posctl.position_smoothing import PositionSmoothing, PositionSmoothingParams

NS = VehicleStatus
YAW_TOWARD_WAYPOINT, YAW_TOWARD_HOME, YAW_AWAY_FROM_HOME, YAW_ALONG_TRAJECTORY, YAW_HOLD = range(5)
_AUTO_NAV_STATES = (
    NS.NAVIGATION_STATE_AUTO_TAKEOFF,
    NS.NAVIGATION_STATE_AUTO_LOITER,
    NS.NAVIGATION_STATE_AUTO_MISSION,
    NS.NAVIGATION_STATE_AUTO_RTL,
    NS.NAVIGATION_STATE_AUTO_LAND,
)
_YAW_ALONG_MIN_SPEED = 0.5


class FlightModeManagerParams(ParamSet):
    """What the manager reads itself, and its position smoothing's (the return, the mission and the manual modes
    take theirs from the same values)."""

    mpc_tko_speed: float
    mis_takeoff_alt: float
    mpc_land_speed: float
    mpc_land_alt1: float
    mpc_land_alt2: float
    mpc_yaw_mode: int
    mpc_yawrauto_max: float
    mpc_vel_manual: float
    mpc_man_y_max: float
    mpc_man_tilt_max: float
    mpc_hold_dz: float
    mpc_hold_max_xy: float
    mpc_hold_max_z: float
    mpc_z_vel_max_up: float
    mpc_z_vel_max_dn: float
    gf_max_hor_dist: float
    gf_max_ver_dist: float
    smoothing: PositionSmoothingParams


PARAMS: tuple[Param, ...] = combine(FlightModeManagerParams.PARAMS, tracker.PARAMS, rtl.PARAMS, feasibility.PARAMS)


class NavigatorInputs(NamedTuple):
    state: VehicleState
    nav_state: int
    armed: bool
    home: HomePosition | None
    request: NavigationRequest | None
    manual: ManualControlSetpoint | None


class FlightModeManager:
    """``load_mission`` on upload, ``update(inputs, dt)`` every cycle (see the module docstring)."""

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._p = FlightModeManagerParams()
        self._values: dict[str, object] = {}
        """The values given so far, by PX4 name (a later ``set_params`` may give only some)."""
        self.smoothing = PositionSmoothing()
        self.rtl = ReturnToLaunch()
        self.yaw = YawSlew()
        self.manual_position = ManualPositionTask({})
        self.manual_altitude = ManualAltitudeTask({})
        self.missions = MissionStore(on_replaced=self._mission_replaced)
        self._active: tuple[int, bool] | None = None
        self._reposition_counter = 0
        self._mission_start_counter = 0
        self._target: Vec3 = (NAN, NAN, NAN)
        self._target_yaw = NAN
        self._speed = NAN
        self._land_xy: tuple[float, float] | None = None
        self._land_vz = 0.0
        self._mission_returning = False
        self._smoothing_key: tuple[float, float, float] | None = None
        self.set_params(params or {})

    # ------------------------------------------------------------------ configuration

    def set_params(self, params: Mapping[str, object]) -> None:
        self._values.update(params)
        self._p = FlightModeManagerParams.from_params(self._values)
        self.rtl.set_params(self._values)
        self.manual_position.set_params(self._values)
        self.manual_altitude.set_params(self._values)
        self.missions.set_params(self._values)
        self._smoothing_key = None

    def _configure_smoothing(self, cruise: float = NAN, climb: float = NAN, radius: float = NAN) -> None:
        key = (cruise, climb, radius)
        if key == self._smoothing_key:
            return
        p = self._p
        self._smoothing_key = key
        self.smoothing.set_params(
            replace(
                p.smoothing,
                mpc_xy_cruise=cruise if math.isfinite(cruise) and cruise > 0.0 else p.smoothing.mpc_xy_cruise,
                mpc_z_v_auto_up=climb if math.isfinite(climb) else p.smoothing.mpc_z_v_auto_up,
                nav_acc_rad=radius if math.isfinite(radius) and radius > 0.0 else p.smoothing.nav_acc_rad,
            )
        )

    # ------------------------------------------------------------------ missions

    @property
    def mission(self) -> Mission | None:
        return self.missions.mission

    @property
    def tracker(self) -> MissionTracker | None:
        return self.missions.tracker

    def load_mission(self, mission: Mission, mission_id: int) -> str:
        """Take an uploaded mission; returns why it was refused ("" when accepted)."""
        return self.missions.load(mission, mission_id, self._values)

    def load_mission_refused(self, mission_id: int, reason: str) -> None:
        """An upload that could not even be read: no mission, and the reason for ``mission_result``."""
        self.missions.refuse(mission_id, reason)

    def _mission_replaced(self) -> None:
        self._mission_returning = False
        if self._active is not None and self._active[0] == NS.NAVIGATION_STATE_AUTO_MISSION:
            self._active = None  # restart the mission task with the new mission on the next update

    def mission_status(self) -> MissionStatus:
        return self.missions.status()

    # ------------------------------------------------------------------ cycle

    def update(self, inp: NavigatorInputs, dt: float) -> TrajectoryCommand | None:
        """The trajectory setpoint for this cycle, or None when the mode flies without one."""
        if math.isinf(inp.state.yaw):  # no heading, as NaN says (the trigonometry raises on infinity)
            inp = inp._replace(state=inp.state._replace(yaw=NAN))
        if not inp.armed:
            self._active = None
            return None
        key = (inp.nav_state, inp.armed)
        if key != self._active:
            if inp.nav_state in _AUTO_NAV_STATES and not _position_known(inp.state):
                # An auto mode takes its targets from the position: descend until it is known, then start.
                return self._descend(inp.state, inp.home, dt)
            previous, self._active = self._active, key
            if not self._activate(inp, previous[0] if previous is not None else None):
                self._active = None
                return None
        return self._run(inp, dt)

    def _activate(self, inp: NavigatorInputs, previous: int | None) -> bool:
        state = inp.state
        nav = inp.nav_state
        after_takeoff = previous == NS.NAVIGATION_STATE_AUTO_TAKEOFF and nav == NS.NAVIGATION_STATE_AUTO_LOITER
        if not after_takeoff:
            self.yaw.reset(state.yaw)
            self._target_yaw = NAN
        self._land_xy = None
        self._land_vz = _descent_rate(state)
        self._speed = NAN
        if nav == NS.NAVIGATION_STATE_POSCTL:
            self.manual_position.activate(state)
            return True
        if nav == NS.NAVIGATION_STATE_ALTCTL:
            self.manual_altitude.activate(state)
            return True
        if nav == NS.NAVIGATION_STATE_DESCEND:
            return True
        if nav not in _AUTO_NAV_STATES:
            return False
        if after_takeoff:
            # Like PX4's navigator, Hold after a takeoff keeps the takeoff point; the trajectory goes on.
            self._take_reposition(inp)
            return True
        self._reset_smoothing(state)
        if nav == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
            self._start_takeoff(inp)
        elif nav == NS.NAVIGATION_STATE_AUTO_LOITER:
            self._target = self._stopping_point(state)
            self._take_reposition(inp)
        elif nav == NS.NAVIGATION_STATE_AUTO_MISSION:
            self._start_mission(inp)
        elif nav == NS.NAVIGATION_STATE_AUTO_RTL:
            self._start_return(inp)
        return True

    def _run(self, inp: NavigatorInputs, dt: float) -> TrajectoryCommand | None:
        nav = inp.nav_state
        state = inp.state
        if nav == NS.NAVIGATION_STATE_POSCTL:
            return self.manual_position.update(state, inp.manual, dt)
        if nav == NS.NAVIGATION_STATE_ALTCTL:
            return self.manual_altitude.update(state, inp.manual, dt)
        if nav == NS.NAVIGATION_STATE_DESCEND or not _position_known(state):
            return self._descend(state, inp.home, dt)
        if nav == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
            return self._takeoff(state, dt)
        if nav == NS.NAVIGATION_STATE_AUTO_LOITER:
            self._take_reposition(inp)
            return self._fly_to(state, self._target, dt, yaw=self._target_yaw)
        if nav == NS.NAVIGATION_STATE_AUTO_MISSION:
            if inp.request is not None and inp.request.mission_start_counter != self._mission_start_counter:
                self._start_mission(inp)
            return self._mission(inp, dt)
        if nav == NS.NAVIGATION_STATE_AUTO_RTL:
            return self._return(inp, dt)
        if nav == NS.NAVIGATION_STATE_AUTO_LAND:
            return self._land(state, inp.home, dt)
        return None

    # ------------------------------------------------------------------ building blocks

    def _reset_smoothing(self, state: VehicleState) -> None:
        velocity = tuple(v if math.isfinite(v) else 0.0 for v in state.velocity)
        position = state.position if _position_known(state) else (0.0, 0.0, 0.0)
        self.smoothing.reset(position, velocity, (0.0, 0.0, 0.0))

    def _fly_to(
        self,
        state: VehicleState,
        target: Vec3,
        dt: float,
        *,
        yaw: float = NAN,
        previous: Vec3 | None = None,
        following: Vec3 | None = None,
        radius: float = NAN,
        climb: float = NAN,
        yaw_mode: int = YAW_HOLD,
        home: HomePosition | None = None,
    ) -> TrajectoryCommand:
        self._configure_smoothing(self._speed, climb, radius)
        single = previous is None
        point = self.smoothing.generate(
            dt,
            state.position,
            (previous or target, target, following or target),
            is_single_waypoint=single,
            stop_at_target=following is None,
        )
        if not math.isfinite(yaw):
            yaw = self._heading(yaw_mode, state, target, point.velocity, home)
        yaw_sp, yawspeed = self.yaw.update(yaw, dt, math.radians(self._p.mpc_yawrauto_max))
        return TrajectoryCommand(point.position, point.velocity, point.acceleration, point.jerk, yaw_sp, yawspeed)

    def _heading(
        self, mode: int, state: VehicleState, target: Vec3, velocity: Vec3, home: HomePosition | None
    ) -> float:
        px, py = state.position[0], state.position[1]
        if mode == YAW_TOWARD_WAYPOINT:
            dx, dy = target[0] - px, target[1] - py
            return math.atan2(dy, dx) if math.hypot(dx, dy) > self._p.smoothing.nav_acc_rad else NAN
        if mode in (YAW_TOWARD_HOME, YAW_AWAY_FROM_HOME) and home is not None:
            dx, dy = home.x - px, home.y - py
            if math.hypot(dx, dy) <= self._p.smoothing.nav_acc_rad:
                return NAN
            bearing = math.atan2(dy, dx)
            return bearing if mode == YAW_TOWARD_HOME else bearing + math.pi
        if mode == YAW_ALONG_TRAJECTORY and math.hypot(velocity[0], velocity[1]) > _YAW_ALONG_MIN_SPEED:
            return math.atan2(velocity[1], velocity[0])
        return NAN

    def _hold_heading(self, dt: float, target: float = NAN) -> tuple[float, float]:
        return self.yaw.update(target, dt, math.radians(self._p.mpc_yawrauto_max))

    # ------------------------------------------------------------------ takeoff

    def _start_takeoff(self, inp: NavigatorInputs) -> None:
        state, home, request = inp.state, inp.home, inp.request
        altitude = request.takeoff_altitude if request is not None else NAN
        if not (math.isfinite(altitude) and altitude > 0.0):
            altitude = self._p.mis_takeoff_alt
        ground_z = home.z if home is not None else state.position[2]
        self._target = (state.position[0], state.position[1], ground_z - altitude)
        self._target_yaw = request.takeoff_yaw if request is not None else NAN

    def _takeoff(self, state: VehicleState, dt: float, target: Vec3 | None = None) -> TrajectoryCommand:
        target = target or self._target
        if not state.flying:
            # Until the position controller's thrust ramp is done, ask for a climb rate (PX4's takeoff
            # trigger) and keep the trajectory at the vehicle so it continues smoothly from there.
            self._reset_smoothing(state)
            yaw, yawspeed = self._hold_heading(dt, self._target_yaw)
            return TrajectoryCommand(
                position=(target[0], target[1], NAN),
                velocity=(NAN, NAN, -self._p.mpc_tko_speed),
                yaw=yaw,
                yawspeed=yawspeed,
            )
        return self._fly_to(state, target, dt, yaw=self._target_yaw, climb=self._p.mpc_tko_speed)

    # ------------------------------------------------------------------ hold and go-to

    def _take_reposition(self, inp: NavigatorInputs) -> None:
        request = inp.request
        if request is None or request.reposition_counter == self._reposition_counter:
            return
        self._reposition_counter = request.reposition_counter
        position = inp.state.position
        self._target = tuple(t if math.isfinite(t) else p for t, p in zip(request.reposition, position, strict=True))
        self._target_yaw = request.reposition_yaw
        self._speed = request.reposition_speed

    # ------------------------------------------------------------------ mission

    def _start_mission(self, inp: NavigatorInputs) -> None:
        if self.tracker is None:
            return
        request = inp.request
        first = -1
        if request is not None and request.mission_start_counter != self._mission_start_counter:
            self._mission_start_counter = request.mission_start_counter
            # An item set for a mission that was replaced since (a longer one) does not apply to this one.
            if request.mission_start_index < self.tracker.progress.seq_total:
                first = request.mission_start_index
        self.missions.start(inp.state.now_us, inp.state.position, first, inp.home)
        self._mission_returning = False
        self._land_xy = None

    def _mission(self, inp: NavigatorInputs, dt: float) -> TrajectoryCommand:
        state = inp.state
        if self.tracker is None or self.mission is None:
            return self._fly_to(state, self._stopping_point(state), dt)
        if self._mission_returning:
            return self._return(inp, dt)
        progress = self.tracker.update(state.now_us, state.position, state.yaw, state.landed)
        if progress.return_requested:
            self._mission_returning = True
            self._start_return(inp)
            return self._return(inp, dt)
        self._speed = progress.cruise_speed
        item = self.mission[progress.seq_current]
        if progress.command == MAV_CMD_NAV_LAND:
            return self._land(state, inp.home, dt, at=(progress.target[0], progress.target[1]))
        if progress.finished:
            return self._fly_to(state, progress.target, dt, yaw=progress.target_yaw)
        if progress.command == MAV_CMD_NAV_TAKEOFF:
            self._target_yaw = progress.target_yaw
            return self._takeoff(state, dt, progress.target)
        following = self._following_target(progress.seq_current, progress.target, inp.home)
        return self._fly_to(
            state,
            progress.target,
            dt,
            yaw=progress.target_yaw,
            previous=progress.previous if _finite3(progress.previous) else None,
            following=following,
            radius=item.acceptance_radius,
            yaw_mode=self._p.mpc_yaw_mode,
            home=inp.home,
        )

    def _following_target(self, seq: int, target: Vec3, home: HomePosition | None) -> Vec3 | None:
        """The next leg's end when the vehicle may turn onto it without stopping, else None (stop)."""
        assert self.mission is not None
        item = self.mission[seq]
        if item.command != MAV_CMD_NAV_WAYPOINT or item.hold_time > 0.0 or not item.autocontinue:
            return None
        for following in self.mission.items[seq + 1 :]:
            if not following.has_position:
                continue
            if following.command != MAV_CMD_NAV_WAYPOINT or not _finite3(following.position):
                return None
            hx, hy, hz = home.position if home is not None else (0.0, 0.0, 0.0)
            return (hx + following.north, hy + following.east, hz + following.down)
        return None

    # ------------------------------------------------------------------ return and land

    def _start_return(self, inp: NavigatorInputs) -> None:
        self._land_xy = None
        if inp.home is not None:
            self.rtl.start(inp.state.now_us, inp.state.position, inp.home)

    def _return(self, inp: NavigatorInputs, dt: float) -> TrajectoryCommand:
        state, home = inp.state, inp.home
        if home is None:
            return self._fly_to(state, self._stopping_point(state), dt)
        sp = self.rtl.update(state.now_us, state.position, state.landed)
        if sp.phase in (RtlPhase.LAND, RtlPhase.LANDED):
            return self._land(state, home, dt, yaw=home.yaw, at=(home.x, home.y))
        mode = self._p.mpc_yaw_mode if sp.phase == RtlPhase.RETURN else YAW_HOLD
        return self._fly_to(state, sp.position, dt, yaw=sp.yaw, yaw_mode=mode, home=home)

    def _land(
        self,
        state: VehicleState,
        home: HomePosition | None,
        dt: float,
        yaw: float = NAN,
        at: tuple[float, float] | None = None,
    ) -> TrajectoryCommand:
        """Land at ``at`` (default: where the vehicle can stop), chosen when the landing starts."""
        if self._land_xy is None:
            stop = self._stopping_point(state)
            self._land_xy = at or (stop[0], stop[1])
            self._land_vz = _descent_rate(state)
        # The trajectory keeps its own height; the descent is a velocity setpoint below it.
        hold_z = self.smoothing.point().position[2]
        point = self._fly_to(state, (self._land_xy[0], self._land_xy[1], hold_z), dt, yaw=yaw)
        self._land_vz = self._slew_descent(self._land_speed(state, home), dt)
        return point._replace(
            position=(point.position[0], point.position[1], NAN),
            velocity=(point.velocity[0], point.velocity[1], self._land_vz),
            acceleration=(point.acceleration[0], point.acceleration[1], NAN),
            jerk=(point.jerk[0], point.jerk[1], NAN),
        )

    def _stopping_point(self, state: VehicleState) -> Vec3:
        return stopping_point(state.position, state.velocity, self._p.smoothing.mpc_acc_hor)

    def _land_speed(self, state: VehicleState, home: HomePosition | None) -> float:
        p = self._p
        if home is None or not math.isfinite(state.position[2]):
            return p.mpc_land_speed
        height = home.z - state.position[2]
        return interpolate(height, p.mpc_land_alt2, p.mpc_land_alt1, p.mpc_land_speed, p.smoothing.mpc_z_v_auto_dn)

    def _slew_descent(self, target: float, dt: float) -> float:
        step = self._p.smoothing.mpc_acc_down_max * dt
        return max(self._land_vz - step, min(self._land_vz + step, target))

    def _descend(self, state: VehicleState, home: HomePosition | None, dt: float) -> TrajectoryCommand:
        """Descending at the landing rate with no horizontal acceleration: all that is left without a position
        (the position controller still leans into the wind it had learned)."""
        self._land_vz = self._slew_descent(self._p.mpc_land_speed, dt)
        yaw, yawspeed = self._hold_heading(dt)
        return TrajectoryCommand(
            velocity=(NAN, NAN, self._land_vz), acceleration=(0.0, 0.0, NAN), yaw=yaw, yawspeed=yawspeed
        )


def _finite3(v: Vec3) -> bool:
    return math.isfinite(v[0]) and math.isfinite(v[1]) and math.isfinite(v[2])


def _descent_rate(state: VehicleState) -> float:
    vz = state.velocity[2]
    return vz if math.isfinite(vz) and vz > 0.0 else 0.0


def _position_known(state: VehicleState) -> bool:
    return _finite3(state.position)
