"""FlightModeManager: takeoff, hold, go-to, mission, return, land and descend, flown on a kinematic plant.

The plant flies every setpoint exactly (a position component where one is set, else the velocity
integrated) above flat ground at z = 0, so what is checked is the setpoint stream itself: where it
leads, in what order, and within which speed, acceleration and jerk limits.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import pytest

from stack.commander import commands as C
from stack.commander.home import HomePosition
from stack.commander.module import navigation_request
from stack.commander.rtl import RtlPhase
from stack.commander.state_machine import Commander
from stack.mathlib.scalar import wrap_pi
from stack.mathlib.vector import Vec3
from stack.mission.items import MAV_CMD_NAV_WAYPOINT, MAV_FRAME_LOCAL_NED, Mission, MissionItem
from stack.mission.waypoints import parse_waypoint_list
from stack.msg.navigation import NavigationRequest
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus as NS
from stack.posctl.flight_mode_manager import FlightModeManager, NavigatorInputs
from stack.posctl.flight_task import TrajectoryCommand, VehicleState
from tests.commander.helpers import healthy

DT = 0.02
NAN = math.nan
HOME = HomePosition(0.0, 0.0, 0.0, 0.0)
LEAVE_GROUND = 0.3
"""Height [m] above ground at which the plant reports its takeoff ramp done ("flying")."""
AUTO_MODES = (
    NS.NAVIGATION_STATE_AUTO_TAKEOFF,
    NS.NAVIGATION_STATE_AUTO_LOITER,
    NS.NAVIGATION_STATE_AUTO_MISSION,
    NS.NAVIGATION_STATE_AUTO_RTL,
    NS.NAVIGATION_STATE_AUTO_LAND,
)


@dataclass
class Flight:
    """A FlightModeManager flying a perfect-tracking point on a fixed 50 Hz clock."""

    position: Vec3 = (0.0, 0.0, 0.0)
    velocity: Vec3 = (0.0, 0.0, 0.0)
    yaw: float = 0.0
    nav_state: int = NS.NAVIGATION_STATE_AUTO_LOITER
    params: dict[str, object] = field(default_factory=dict)
    home: HomePosition | None = HOME
    request: NavigationRequest | None = None
    manual: ManualControlSetpoint | None = None
    armed: bool = True
    t_us: int = 1_000_000
    flying: bool = False

    def __post_init__(self) -> None:
        self.fmm = FlightModeManager(self.params)
        self.flying = self.flying or self.position[2] < -LEAVE_GROUND

    @property
    def landed(self) -> bool:
        return self.position[2] >= 0.0 and self.velocity[2] >= 0.0

    def state(self) -> VehicleState:
        return VehicleState(self.t_us, self.position, self.velocity, self.yaw, self.landed, self.flying)

    def inputs(self) -> NavigatorInputs:
        return NavigatorInputs(self.state(), self.nav_state, self.armed, self.home, self.request, self.manual)

    def step(self) -> TrajectoryCommand | None:
        command = self.fmm.update(self.inputs(), DT)
        self.t_us += round(DT * 1e6)
        if command is not None:
            self._follow(command)
        return command

    def run(self, seconds: float) -> list[TrajectoryCommand]:
        commands = []
        for _ in range(round(seconds / DT)):
            command = self.step()
            assert command is not None
            commands.append(command)
        return commands

    def _follow(self, command: TrajectoryCommand) -> None:
        position, velocity = [], []
        for p, p_sp, v_sp in zip(self.position, command.position, command.velocity, strict=True):
            if math.isfinite(p_sp):
                position.append(p_sp)
                velocity.append(v_sp if math.isfinite(v_sp) else (p_sp - p) / DT)
            elif math.isfinite(v_sp):
                position.append(p + v_sp * DT)
                velocity.append(v_sp)
            else:
                position.append(p)
                velocity.append(0.0)
        if position[2] >= 0.0:
            position[2], velocity[2] = 0.0, 0.0
        self.position = (position[0], position[1], position[2])
        self.velocity = (velocity[0], velocity[1], velocity[2])
        if math.isfinite(command.yaw):
            self.yaw = command.yaw
        self.flying = self.position[2] < -LEAVE_GROUND or (self.flying and not self.landed)


def horizontal(v: Vec3) -> float:
    return math.hypot(v[0], v[1])


def horizontal_distance(a: Vec3, b: Vec3) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


def assert_auto_limits(commands: list[TrajectoryCommand], cruise: float, acc: float, jerk: float) -> None:
    """Horizontal speed within the cruise speed (2 % slack: the per-axis profiles can exceed it briefly in a
    turn, as in test_position_smoothing); per-axis acceleration and jerk within their limits."""
    for c in commands:
        assert horizontal(c.velocity) <= cruise * 1.02
        assert abs(c.acceleration[0]) <= acc + 1e-6 and abs(c.acceleration[1]) <= acc + 1e-6
        assert max(abs(j) for j in c.jerk) <= jerk + 1e-6


def assert_yaw_rate_limited(commands: list[TrajectoryCommand], max_rate_deg: float) -> None:
    step = math.radians(max_rate_deg) * DT + 1e-9
    for a, b in itertools.pairwise(commands):
        assert abs(wrap_pi(b.yaw - a.yaw)) <= step


def assert_brakes_and_stays(flight: Flight, stopping_x: float) -> None:
    """Moving north at level flight, the vehicle comes to rest at or beyond the stopping point at MPC_ACC_HOR
    (where it aims while braking, re-aimed every cycle), never turning back, and then stays there."""
    altitude = flight.position[2]
    commands = flight.run(15.0)
    assert all(c.velocity[0] >= -1e-9 for c in commands)
    assert all(c.position[1:] == pytest.approx((0.0, altitude)) for c in commands)
    rest = flight.position
    assert rest[0] >= stopping_x - 1e-6
    flight.run(5.0)
    assert flight.position == pytest.approx(rest, abs=1e-6)


# ---------------------------------------------------------------------------------------------- takeoff


def test_takeoff_asks_for_the_takeoff_climb_rate_until_the_thrust_ramp_is_done():
    flight = Flight(position=(2.0, -1.0, 0.0), nav_state=NS.NAVIGATION_STATE_AUTO_TAKEOFF)
    flight.request = NavigationRequest(takeoff_altitude=5.0)
    command = flight.fmm.update(flight.inputs(), DT)
    assert command is not None
    assert command.position[:2] == (2.0, -1.0) and math.isnan(command.position[2])
    assert math.isnan(command.velocity[0]) and math.isnan(command.velocity[1])
    assert command.velocity[2] == -1.5  # MPC_TKO_SPEED, up


def test_takeoff_climbs_to_the_requested_altitude_above_home_and_stops_there():
    home = HomePosition(0.0, 0.0, 1.0, 0.0)  # home 1 m below the local origin
    flight = Flight(position=(0.0, 0.0, 1.0), nav_state=NS.NAVIGATION_STATE_AUTO_TAKEOFF, home=home)
    flight.request = NavigationRequest(takeoff_altitude=5.0)
    commands = flight.run(25.0)
    assert flight.position == pytest.approx((0.0, 0.0, -4.0), abs=0.02)
    assert all(c.velocity[2] >= -1.5 - 1e-9 for c in commands)  # never faster than MPC_TKO_SPEED
    assert all(c.position[2] >= -4.0 - 1e-6 for c in commands if math.isfinite(c.position[2]))  # no overshoot
    assert all(c.position[:2] == (0.0, 0.0) for c in commands)


def test_takeoff_without_an_altitude_uses_mis_takeoff_alt():
    flight = Flight(nav_state=NS.NAVIGATION_STATE_AUTO_TAKEOFF, params={"MIS_TAKEOFF_ALT": 3.5})
    flight.request = NavigationRequest(takeoff_altitude=-2.0)  # invalid: the default applies
    flight.run(25.0)
    assert flight.position[2] == pytest.approx(-3.5, abs=0.02)


def _fly_with_commander(flight: Flight, commander: Commander, seconds: float) -> list[str]:
    """Close the loop through the commander: its mode and navigation request drive the manager."""
    events: list[str] = []
    for _ in range(round(seconds / DT)):
        out = commander.update(flight.t_us, healthy(flight.t_us, flight.position, flight.landed))
        events.extend(out.events)
        flight.nav_state = out.vehicle_status.nav_state
        flight.armed = out.vehicle_status.arming_state == NS.ARMING_STATE_ARMED
        flight.request = navigation_request(out.navigation)
        flight.step()
    return events


def test_takeoff_command_reports_done_and_hold_then_keeps_the_takeoff_point():
    commander = Commander({"COM_FAIL_ACT_T": 0.0})
    flight = Flight(position=(3.0, 4.0, 0.0), nav_state=NS.NAVIGATION_STATE_MANUAL, armed=False)
    commander.update(flight.t_us, healthy(flight.t_us, flight.position))
    assert commander.handle_command(C.takeoff_command(6.0), flight.t_us).reason == ""
    events = _fly_with_commander(flight, commander, 8.0)
    assert "Takeoff complete, switching to Hold" in events
    assert flight.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    # The commander switched within NAV_MC_ALT_RAD of 6 m; Hold carries on to the takeoff point itself.
    _fly_with_commander(flight, commander, 15.0)
    assert flight.position == pytest.approx((3.0, 4.0, -6.0), abs=0.02)


def test_hold_after_takeoff_keeps_the_takeoff_target_while_a_fresh_hold_stops_where_it_is():
    flight = Flight(nav_state=NS.NAVIGATION_STATE_AUTO_TAKEOFF)
    flight.request = NavigationRequest(takeoff_altitude=5.0)
    while flight.position[2] > -4.2:  # inside NAV_MC_ALT_RAD of the target, still climbing
        flight.step()
    climbing_at = flight.position
    flight.nav_state = NS.NAVIGATION_STATE_AUTO_LOITER
    flight.run(20.0)
    assert flight.position == pytest.approx((0.0, 0.0, -5.0), abs=0.01)

    fresh = Flight(position=climbing_at)
    fresh.run(20.0)
    assert fresh.position == pytest.approx(climbing_at, abs=0.01)


# ---------------------------------------------------------------------------------------------- hold and go-to


def test_hold_brakes_to_the_stopping_point_at_mpc_acc_hor():
    # 3 m/s north braking at 3 m/s²: v²/2a = 1.5 m further on.
    flight = Flight(position=(0.0, 0.0, -10.0), velocity=(3.0, 0.0, 0.0))
    flight.run(15.0)
    assert flight.position == pytest.approx((1.5, 0.0, -10.0), abs=0.01)


def test_hold_at_rest_keeps_the_position_exactly():
    flight = Flight(position=(4.0, -3.0, -7.0), yaw=0.4)
    commands = flight.run(5.0)
    assert all(c.position == (4.0, -3.0, -7.0) and c.yaw == pytest.approx(0.4) for c in commands)


def test_goto_reaches_its_target_within_the_auto_limits():
    flight = Flight(position=(0.0, 0.0, -10.0))
    flight.run(0.5)
    flight.request = NavigationRequest(reposition=(30.0, 40.0, -10.0), reposition_counter=1)
    commands = flight.run(40.0)
    assert flight.position == pytest.approx((30.0, 40.0, -10.0), abs=0.01)
    assert_auto_limits(commands, cruise=5.0, acc=3.0, jerk=4.0)
    # A 50 m leg reaches the cruise speed; the altitude is kept.
    assert max(horizontal(c.velocity) for c in commands) == pytest.approx(5.0, abs=1e-3)
    assert all(c.position[2] == pytest.approx(-10.0) for c in commands)


def test_goto_uses_the_cruise_acceleration_and_jerk_parameters():
    params = {"MPC_XY_CRUISE": 8.0, "MPC_ACC_HOR": 2.0, "MPC_JERK_AUTO": 2.0}
    flight = Flight(position=(0.0, 0.0, -10.0), params=params)
    flight.request = NavigationRequest(reposition=(100.0, 0.0, -10.0), reposition_counter=1)
    commands = flight.run(40.0)
    assert_auto_limits(commands, cruise=8.0, acc=2.0, jerk=2.0)
    assert max(c.velocity[0] for c in commands) == pytest.approx(8.0, abs=1e-3)
    assert max(c.acceleration[0] for c in commands) == pytest.approx(2.0, abs=1e-3)
    assert max(c.jerk[0] for c in commands) == pytest.approx(2.0, abs=1e-6)
    assert flight.position == pytest.approx((100.0, 0.0, -10.0), abs=0.01)


def test_goto_flies_at_the_requested_speed():
    flight = Flight(position=(0.0, 0.0, -10.0))
    flight.request = NavigationRequest(reposition=(0.0, 60.0, -10.0), reposition_speed=3.0, reposition_counter=1)
    commands = flight.run(30.0)
    assert max(horizontal(c.velocity) for c in commands) == pytest.approx(3.0, abs=1e-3)
    assert flight.position == pytest.approx((0.0, 60.0, -10.0), abs=0.01)


def test_goto_nan_components_keep_the_current_position_and_yaw_turns_at_the_rate_limit():
    flight = Flight(position=(5.0, 0.0, -8.0))
    flight.request = NavigationRequest(reposition=(NAN, 10.0, NAN), reposition_yaw=math.pi / 2, reposition_counter=1)
    commands = flight.run(15.0)
    assert flight.position == pytest.approx((5.0, 10.0, -8.0), abs=0.01)
    assert_yaw_rate_limited(commands, 45.0)
    assert commands[-1].yaw == pytest.approx(math.pi / 2)
    # 90° at MPC_YAWRAUTO_MAX 45°/s takes 2 s.
    assert commands[round(1.0 / DT) - 1].yaw == pytest.approx(math.pi / 4, abs=1e-6)


def test_goto_is_taken_once_per_counter():
    flight = Flight(position=(0.0, 0.0, -10.0))
    flight.request = NavigationRequest(reposition=(10.0, 0.0, -10.0), reposition_counter=4)
    flight.run(15.0)
    flight.request = NavigationRequest(reposition=(-10.0, 0.0, -10.0), reposition_counter=4)  # same counter
    flight.run(5.0)
    assert flight.position == pytest.approx((10.0, 0.0, -10.0), abs=0.01)
    flight.request = NavigationRequest(reposition=(-10.0, 0.0, -10.0), reposition_counter=5)
    flight.run(15.0)
    assert flight.position == pytest.approx((-10.0, 0.0, -10.0), abs=0.01)


# ---------------------------------------------------------------------------------------------- mission

MISSION = parse_waypoint_list(
    """\
takeoff 5
20 0 -5
wp 20 20 -5 - - 3
-10 20 -8
land
"""
)


def _fly_mission(flight: Flight, seconds: float) -> list[tuple[int, Vec3]]:
    """Fly until finished (or ``seconds``); returns (item, position it was judged at) as items are reached."""
    reached: list[tuple[int, Vec3]] = []
    last = -1
    for _ in range(round(seconds / DT)):
        judged_at = flight.position
        flight.step()
        status = flight.fmm.mission_status()
        if status.seq_reached != last:
            reached.append((status.seq_reached, judged_at))
            last = status.seq_reached
        if status.finished:
            break
    return reached


def test_mission_visits_each_item_in_order_within_its_acceptance_radius_and_lands():
    flight = Flight(nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    assert flight.fmm.load_mission(MISSION, 7) == ""
    flight.request = NavigationRequest(mission_start_index=0, mission_start_counter=1)
    reached = _fly_mission(flight, 120.0)
    assert [seq for seq, _ in reached] == [0, 1, 2, 3, 4]
    assert reached[0][1][2] <= -5.0 + 0.8  # takeoff: within NAV_MC_ALT_RAD of 5 m
    for seq, position in reached[1:4]:
        item = MISSION[seq]
        radius = item.acceptance_radius or 2.0  # NAV_ACC_RAD
        assert horizontal_distance(position, item.position) <= radius
        assert abs(position[2] - item.down) <= 0.8
    status = flight.fmm.mission_status()
    assert (status.mission_id, status.valid, status.finished, status.seq_total) == (7, True, True, 5)
    assert flight.landed
    assert horizontal_distance(flight.position, (-10.0, 20.0, 0.0)) <= 2.0


def test_mission_turns_inside_a_wide_acceptance_radius_and_respects_the_limits():
    mission = parse_waypoint_list("0 0 -5\n40 0 -5 - - 8\n40 40 -5\n")
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(mission, 1)
    commands = flight.run(40.0)
    assert_auto_limits(commands, cruise=5.0, acc=3.0, jerk=4.0)
    # It cuts the corner (never through the corner point itself) but passes inside the 8 m radius.
    closest = min(math.dist(c.position, (40.0, 0.0, -5.0)) for c in commands)
    assert 0.5 < closest <= 8.0
    # Through the corner without stopping.
    assert min(horizontal(c.velocity) for c in commands[round(5.0 / DT) : round(15.0 / DT)]) > 1.0
    assert flight.position == pytest.approx((40.0, 40.0, -5.0), abs=0.01)
    assert flight.fmm.mission_status().finished


def test_mission_flies_through_a_straight_on_waypoint_at_cruise_speed_but_stops_at_a_held_one():
    def slowest_near_the_waypoint(mission_text: str) -> float:
        flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
        flight.fmm.load_mission(parse_waypoint_list(mission_text), 1)
        commands = flight.run(15.0)
        return min(horizontal(c.velocity) for c in commands if 19.0 < c.position[0] < 21.0)

    assert slowest_near_the_waypoint("20 0 -5\n40 0 -5\n") == pytest.approx(5.0, abs=1e-3)
    assert slowest_near_the_waypoint("20 0 -5 - 5\n40 0 -5\n") < 0.1  # a 5 s hold: all but stopped


def test_mission_speed_item_sets_the_cruise_speed():
    mission = parse_waypoint_list("speed 3\n0 50 -5\n")
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(mission, 1)
    commands = flight.run(30.0)
    assert max(horizontal(c.velocity) for c in commands) == pytest.approx(3.0, abs=1e-3)
    assert flight.position == pytest.approx((0.0, 50.0, -5.0), abs=0.01)


def test_mission_items_are_about_home():
    home = HomePosition(10.0, -5.0, 2.0, 0.0)
    mission = parse_waypoint_list("0 10 -5\n")
    flight = Flight(position=(10.0, -5.0, -3.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION, home=home)
    flight.fmm.load_mission(mission, 1)
    flight.run(15.0)
    assert flight.position == pytest.approx((10.0, 5.0, -3.0), abs=0.01)


def test_mission_start_request_begins_at_the_requested_item():
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(parse_waypoint_list("10 0 -5\n0 10 -5\n"), 1)
    flight.request = NavigationRequest(mission_start_index=1, mission_start_counter=1)
    reached = _fly_mission(flight, 20.0)
    assert [seq for seq, _ in reached] == [1]
    assert flight.fmm.mission_status().finished
    assert flight.position[0] == pytest.approx(0.0, abs=1e-6)  # never went to item 0


def test_infeasible_mission_is_refused_and_mission_mode_holds():
    flight = Flight(position=(2.0, 0.0, -5.0), velocity=(3.0, 0.0, 0.0), params={"GF_MAX_HOR_DIST": 30.0})
    flight.nav_state = NS.NAVIGATION_STATE_AUTO_MISSION
    reason = flight.fmm.load_mission(parse_waypoint_list("50 0 -5\n"), 9)
    assert "outside the geofence (GF_MAX_HOR_DIST 30 m)" in reason
    status = flight.fmm.mission_status()
    assert (status.mission_id, status.valid, status.reason, status.seq_reached) == (9, False, reason, -1)
    assert flight.fmm.mission is None
    assert_brakes_and_stays(flight, stopping_x=3.5)


def test_a_new_upload_in_mission_mode_flies_the_new_mission():
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(parse_waypoint_list("50 0 -5\n"), 1)
    flight.run(3.0)
    assert flight.fmm.load_mission(parse_waypoint_list("0 30 -5\n"), 2) == ""
    flight.run(30.0)
    assert flight.position == pytest.approx((0.0, 30.0, -5.0), abs=0.01)
    status = flight.fmm.mission_status()
    assert (status.mission_id, status.finished, status.seq_total) == (2, True, 1)


def test_an_unreadable_upload_leaves_no_mission_and_reports_why():
    flight = Flight(position=(0.0, 0.0, -5.0))
    flight.fmm.load_mission(parse_waypoint_list("10 0 -5\n"), 1)
    flight.fmm.load_mission_refused(2, "malformed mission: bad item")
    assert flight.fmm.mission is None and flight.fmm.tracker is None
    status = flight.fmm.mission_status()
    assert (status.mission_id, status.valid, status.reason, status.seq_total) == (
        2,
        False,
        "malformed mission: bad item",
        0,
    )


def test_mission_return_item_hands_over_to_return():
    mission = parse_waypoint_list("20 0 -10\nrtl\n")
    flight = Flight(position=(0.0, 0.0, -10.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(mission, 1)
    flight.run(90.0)
    assert flight.fmm.rtl.phase == RtlPhase.LANDED
    assert flight.position == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)


# ---------------------------------------------------------------------------------------------- headings


def _leg_headings(yaw_mode: int, start_yaw: float = 0.3) -> list[TrajectoryCommand]:
    """A 40 m leg east along x = −20 (home at the origin) with MPC_YAW_MODE ``yaw_mode``."""
    mission = Mission((MissionItem(0, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_LOCAL_NED, -20.0, 40.0, -5.0),))
    flight = Flight(
        position=(-20.0, 0.0, -5.0),
        yaw=start_yaw,
        nav_state=NS.NAVIGATION_STATE_AUTO_MISSION,
        params={"MPC_YAW_MODE": yaw_mode},
    )
    flight.fmm.load_mission(mission, 1)
    commands = []
    while flight.position[1] < 20.0:  # half way
        command = flight.step()
        assert command is not None
        commands.append(command)
    return commands


@pytest.mark.parametrize(
    ("yaw_mode", "heading"),
    [
        (0, math.pi / 2),  # toward the waypoint
        (1, -math.pi / 4),  # toward home, from (−20, 20)
        (2, 3 * math.pi / 4),  # away from home
        (3, math.pi / 2),  # along the trajectory
        (4, 0.3),  # hold
    ],
)
def test_mpc_yaw_mode_sets_the_heading_on_mission_legs(yaw_mode, heading):
    commands = _leg_headings(yaw_mode)
    assert commands[-1].yaw == pytest.approx(heading, abs=0.02)
    assert_yaw_rate_limited(commands, 45.0)


def test_yaw_toward_waypoint_turns_at_once_while_along_trajectory_waits_for_speed():
    toward, along = _leg_headings(0), _leg_headings(3)
    assert toward[0].yawspeed == pytest.approx(math.radians(45.0))
    assert along[0].yawspeed == 0.0 and along[0].yaw == pytest.approx(0.3)


def test_item_yaw_overrides_mpc_yaw_mode():
    mission = parse_waypoint_list("0 30 -5 -90\n")
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_MISSION)
    flight.fmm.load_mission(mission, 1)
    commands = flight.run(5.0)
    assert commands[-1].yaw == pytest.approx(-math.pi / 2)


# ---------------------------------------------------------------------------------------------- return


def test_return_climbs_returns_over_home_descends_and_lands():
    flight = Flight(position=(40.0, 30.0, -10.0), nav_state=NS.NAVIGATION_STATE_AUTO_RTL)
    phases: list[tuple[RtlPhase, Vec3]] = []
    commands = []
    for _ in range(round(120.0 / DT)):
        command = flight.step()
        assert command is not None
        commands.append(command)
        phase = flight.fmm.rtl.phase
        if not phases or phases[-1][0] != phase:
            phases.append((phase, flight.position))
        if phase == RtlPhase.LANDED:
            break
    assert [p for p, _ in phases] == [
        RtlPhase.CLIMB,
        RtlPhase.RETURN,
        RtlPhase.DESCEND,
        RtlPhase.LAND,
        RtlPhase.LANDED,
    ]
    by_phase = dict(phases)
    # Climbed straight up to RTL_RETURN_ALT (30 m) before leaving, arrived over home at that altitude.
    assert by_phase[RtlPhase.RETURN] == pytest.approx((40.0, 30.0, -30.0), abs=0.8)
    assert by_phase[RtlPhase.DESCEND] == pytest.approx((0.0, 0.0, -30.0), abs=2.0)
    assert by_phase[RtlPhase.LAND][2] == pytest.approx(-10.0, abs=0.8)  # RTL_DESCEND_ALT
    assert flight.landed and flight.position == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)
    # Never above the return altitude; once moving toward home, within NAV_MC_ALT_RAD of it until over home.
    for c in commands:
        if math.isfinite(c.position[2]):
            assert c.position[2] >= -30.0 - 1e-6
            if horizontal_distance(c.position, (40.0, 30.0, 0.0)) > 1e-6 and horizontal(c.position) > 2.0:
                assert c.position[2] <= -30.0 + 0.8


def test_return_leg_faces_home():
    flight = Flight(position=(0.0, 40.0, -30.0), yaw=0.0, nav_state=NS.NAVIGATION_STATE_AUTO_RTL)
    commands = flight.run(6.0)
    assert flight.fmm.rtl.phase == RtlPhase.RETURN
    assert commands[-1].yaw == pytest.approx(-math.pi / 2)
    assert_yaw_rate_limited(commands, 45.0)


def test_return_without_home_brakes_and_stays():
    flight = Flight(position=(2.0, 0.0, -10.0), velocity=(3.0, 0.0, 0.0), home=None)
    flight.nav_state = NS.NAVIGATION_STATE_AUTO_RTL
    assert_brakes_and_stays(flight, stopping_x=3.5)


# ---------------------------------------------------------------------------------------------- land and descend


def test_land_descends_at_the_auto_then_land_speed_and_never_climbs():
    flight = Flight(position=(5.0, 5.0, -20.0), nav_state=NS.NAVIGATION_STATE_AUTO_LAND)
    samples: list[tuple[float, TrajectoryCommand]] = []
    while not flight.landed:
        height = -flight.position[2]
        command = flight.step()
        assert command is not None
        samples.append((height, command))
        assert flight.t_us < 60_000_000
    for _, c in samples:
        assert c.position[:2] == pytest.approx((5.0, 5.0)) and math.isnan(c.position[2])
        assert c.velocity[2] >= 0.0
    for (_, a), (_, b) in itertools.pairwise(samples):
        assert abs(b.velocity[2] - a.velocity[2]) <= 3.0 * DT + 1e-9  # slewed at MPC_ACC_DOWN_MAX
    rates = {round(h, 1): c.velocity[2] for h, c in samples}
    assert rates[15.0] == pytest.approx(1.5)  # MPC_Z_V_AUTO_DN above MPC_LAND_ALT1 (10 m)
    assert rates[7.5] == pytest.approx(1.1, abs=0.01)  # halfway between ALT2 and ALT1: 0.7 + 0.8 / 2
    assert rates[2.0] == pytest.approx(0.7)  # MPC_LAND_SPEED below MPC_LAND_ALT2 (5 m)
    assert samples[0][1].velocity[2] == pytest.approx(3.0 * DT)  # from rest, at MPC_ACC_DOWN_MAX


def test_land_speed_follows_mpc_land_speed():
    flight = Flight(position=(0.0, 0.0, -3.0), nav_state=NS.NAVIGATION_STATE_AUTO_LAND, params={"MPC_LAND_SPEED": 1.2})
    commands = flight.run(2.0)
    assert commands[-1].velocity[2] == pytest.approx(1.2)


def test_land_while_moving_lands_at_the_stopping_point():
    flight = Flight(position=(0.0, 0.0, -4.0), velocity=(0.0, -2.0, 0.0), nav_state=NS.NAVIGATION_STATE_AUTO_LAND)
    flight.run(20.0)
    assert flight.landed
    assert flight.position == pytest.approx((0.0, -2.0 * 2.0 / 6.0, 0.0), abs=0.01)


def test_land_started_while_climbing_ramps_down_from_zero():
    flight = Flight(position=(0.0, 0.0, -20.0), velocity=(0.0, 0.0, -2.0), nav_state=NS.NAVIGATION_STATE_AUTO_LAND)
    command = flight.step()
    assert command is not None and command.velocity[2] == pytest.approx(3.0 * DT)


def test_descend_is_level_at_the_land_speed_without_a_horizontal_setpoint():
    flight = Flight(position=(1.0, 2.0, -10.0), nav_state=NS.NAVIGATION_STATE_DESCEND)
    commands = flight.run(2.0)
    for c in commands:
        assert all(math.isnan(v) for v in c.position)
        assert math.isnan(c.velocity[0]) and math.isnan(c.velocity[1])
        assert c.acceleration[:2] == (0.0, 0.0)
    assert commands[0].velocity[2] == pytest.approx(3.0 * DT)
    assert commands[-1].velocity[2] == pytest.approx(0.7)


# ---------------------------------------------------------------------------------------------- invalid inputs


@pytest.mark.parametrize("nav_state", AUTO_MODES)
def test_without_a_horizontal_position_every_auto_mode_descends_level(nav_state):
    flight = Flight(position=(NAN, NAN, -10.0), nav_state=nav_state, flying=True)
    flight.fmm.load_mission(MISSION, 1)
    flight.request = NavigationRequest(takeoff_altitude=5.0, mission_start_counter=1)
    for _ in range(100):
        command = flight.fmm.update(flight.inputs(), DT)
        assert command is not None
        assert all(math.isnan(v) for v in command.position)
        assert command.acceleration[:2] == (0.0, 0.0)
        assert 0.0 < command.velocity[2] <= 0.7


@pytest.mark.parametrize("nav_state", AUTO_MODES)
def test_auto_mode_entered_without_a_position_starts_from_the_vehicle_once_it_has_one(nav_state):
    flight = Flight(position=(NAN, NAN, -10.0), nav_state=nav_state, flying=True)
    flight.fmm.load_mission(MISSION, 1)
    flight.request = NavigationRequest(takeoff_altitude=5.0)
    flight.fmm.update(flight.inputs(), DT)
    flight.position = (30.0, -20.0, -10.0)
    for _ in range(10):
        command = flight.fmm.update(flight.inputs(), DT)
        assert command is not None
        assert horizontal_distance(command.position, flight.position) < 0.1
        assert math.isnan(command.position[2]) or abs(command.position[2] + 10.0) < 0.5


def test_nan_velocity_and_heading_still_give_a_finite_position_setpoint():
    flight = Flight(position=(1.0, 2.0, -5.0), velocity=(NAN, NAN, NAN), yaw=NAN)
    command = flight.fmm.update(flight.inputs(), DT)
    assert command is not None and command.position == (1.0, 2.0, -5.0)
    assert command.velocity == (0.0, 0.0, 0.0)
    assert math.isnan(command.yaw)  # no heading known: left uncontrolled


def test_nan_reposition_target_keeps_the_position():
    flight = Flight(position=(1.0, 2.0, -5.0))
    flight.request = NavigationRequest(reposition=(NAN, NAN, NAN), reposition_speed=NAN, reposition_counter=1)
    commands = flight.run(2.0)
    assert all(c.position == pytest.approx((1.0, 2.0, -5.0)) for c in commands)


def test_land_without_home_descends_at_mpc_land_speed():
    flight = Flight(position=(0.0, 0.0, -30.0), nav_state=NS.NAVIGATION_STATE_AUTO_LAND, home=None)
    commands = flight.run(2.0)
    assert commands[-1].velocity[2] == pytest.approx(0.7)


# ---------------------------------------------------------------------------------------------- mode routing


@pytest.mark.parametrize(
    "nav_state",
    [NS.NAVIGATION_STATE_MANUAL, NS.NAVIGATION_STATE_STAB, NS.NAVIGATION_STATE_ACRO, NS.NAVIGATION_STATE_OFFBOARD],
)
def test_modes_without_a_trajectory_give_no_setpoint(nav_state):
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=nav_state)
    assert flight.fmm.update(flight.inputs(), DT) is None


def test_disarmed_gives_no_setpoint_and_rearming_restarts_the_mode():
    flight = Flight(position=(0.0, 0.0, -5.0))
    flight.request = NavigationRequest(reposition=(10.0, 0.0, -5.0), reposition_counter=1)
    flight.run(1.0)
    flight.armed = False
    assert flight.step() is None
    flight.armed = True
    flight.position, flight.velocity = (4.0, 4.0, -5.0), (0.0, 0.0, 0.0)
    command = flight.step()
    assert command is not None and command.position == (4.0, 4.0, -5.0)  # a fresh Hold where it is


def test_position_and_altitude_modes_fly_the_sticks():
    centred = ManualControlSetpoint(valid=True, throttle=0.0)
    flight = Flight(position=(1.0, 2.0, -5.0), nav_state=NS.NAVIGATION_STATE_POSCTL, manual=centred)
    command = flight.step()
    assert command is not None and command.position == (1.0, 2.0, -5.0)
    flight.nav_state = NS.NAVIGATION_STATE_ALTCTL
    command = flight.step()
    assert command is not None
    assert math.isnan(command.position[0]) and command.position[2] == -5.0


def test_a_start_item_set_for_a_longer_mission_is_ignored_by_a_shorter_one():
    flight = Flight(position=(0.0, 0.0, -5.0), nav_state=NS.NAVIGATION_STATE_AUTO_LOITER)
    flight.fmm.load_mission(parse_waypoint_list("10 0 -5\n"), 1)
    flight.request = NavigationRequest(mission_start_index=3, mission_start_counter=1)  # set for an older mission
    flight.run(1.0)
    flight.nav_state = NS.NAVIGATION_STATE_AUTO_MISSION
    reached = _fly_mission(flight, 15.0)
    assert [seq for seq, _ in reached] == [0]
    assert flight.fmm.mission_status().finished
