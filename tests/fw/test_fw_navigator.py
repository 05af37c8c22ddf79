"""The fixed-wing navigator's triplets, worked by hand: takeoff, hold, mission legs and loiters, return and landing."""

from __future__ import annotations

import math

import pytest

from stack.commander.home import HomePosition
from stack.fw.navigator import APPROACH_STRAIGHT_LOITERS, RUNWAY_AHEAD, FixedwingNavigator, FwNavigatorInputs
from stack.mission.items import (
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_LOCAL_NED,
    MAV_FRAME_MISSION,
    Mission,
    MissionItem,
)
from stack.msg.fixedwing import PositionSetpoint
from stack.msg.navigation import NavigationRequest
from stack.msg.system import VehicleStatus

NS = VehicleStatus
SP = PositionSetpoint
HOME = HomePosition(0.0, 0.0, 0.0, 0.0, 47.0, 8.0, 500.0)
PARAMS = {"NAV_LOITER_RAD": 60.0, "RTL_RETURN_ALT": 40.0, "RTL_DESCEND_ALT": 15.0, "FW_LND_ANG": 5.0,
          "NAV_ACC_RAD": 25.0, "NAV_FW_ALT_RAD": 10.0, "MIS_TAKEOFF_ALT": 30.0}


def inputs(nav: int, position, yaw: float = 0.0, **kw) -> FwNavigatorInputs:
    base = dict(now_us=1_000_000, nav_state=nav, armed=True, landed=False, position=position, yaw=yaw, home=HOME,
                request=None, acceptance_radius=math.nan)
    base.update(kw)
    return FwNavigatorInputs(**base)


def test_disarmed_or_without_a_position_there_is_no_triplet() -> None:
    nav = FixedwingNavigator(PARAMS)
    assert nav.update(inputs(NS.NAVIGATION_STATE_AUTO_LOITER, (0.0, 0.0, -20.0), armed=False)) is None
    assert nav.update(inputs(NS.NAVIGATION_STATE_AUTO_LOITER, (math.nan, math.nan, -20.0))) is None


def test_takeoff_climbs_along_the_runway_from_where_it_started() -> None:
    nav = FixedwingNavigator(PARAMS)
    yaw = math.radians(90.0)
    request = NavigationRequest(takeoff_altitude=25.0)
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_TAKEOFF, (1.0, 2.0, 0.0), yaw, landed=True, request=request))
    assert t.current.type == SP.SETPOINT_TYPE_TAKEOFF
    assert (t.previous.x, t.previous.y) == (1.0, 2.0)
    assert t.current.x == pytest.approx(1.0) and t.current.y == pytest.approx(2.0 + RUNWAY_AHEAD)
    assert t.current.z == pytest.approx(-25.0)
    assert nav.runway.heading == yaw


def test_hold_circles_where_it_began_and_a_goto_moves_the_circle() -> None:
    nav = FixedwingNavigator(PARAMS)
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_LOITER, (100.0, 50.0, -30.0)))
    assert t.current.type == SP.SETPOINT_TYPE_LOITER
    assert (t.current.x, t.current.y, t.current.z, t.current.loiter_radius) == (100.0, 50.0, -30.0, 60.0)
    assert not t.current.loiter_direction_counter_clockwise
    goto = NavigationRequest(reposition=(300.0, math.nan, -50.0), reposition_counter=1)
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_LOITER, (110.0, 50.0, -30.0), request=goto))
    assert (t.current.x, t.current.y, t.current.z) == (300.0, 50.0, -50.0)


def _item(i: int, command: int, north: float, east: float, down: float, **kw) -> MissionItem:
    return MissionItem(index=i, command=command, frame=MAV_FRAME_LOCAL_NED, north=north, east=east, down=down, **kw)


MISSION = Mission((
    _item(0, MAV_CMD_NAV_TAKEOFF, 150.0, 0.0, -30.0),
    _item(1, MAV_CMD_NAV_WAYPOINT, 500.0, 0.0, -40.0),
    _item(2, MAV_CMD_NAV_WAYPOINT, 500.0, 300.0, -40.0),
    _item(3, MAV_CMD_NAV_LOITER_TURNS, 300.0, 150.0, -40.0, loiter_turns=1.0, loiter_radius=-70.0),
    MissionItem(index=4, command=MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=MAV_FRAME_MISSION, north=math.nan,
                east=math.nan, down=math.nan),
))


def test_a_mission_flies_legs_with_the_next_waypoint_then_loiters_then_returns() -> None:
    nav = FixedwingNavigator(PARAMS)
    assert nav.missions.load(MISSION, 7, PARAMS) == ""
    start = NavigationRequest(mission_start_counter=1)
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (0.0, 0.0, 0.0), landed=True, request=start))
    assert t.current.type == SP.SETPOINT_TYPE_TAKEOFF and (t.current.x, t.current.y) == (150.0, 0.0)
    # At 22 m the takeoff (30 m, NAV_FW_ALT_RAD 10 m) is reached: the first leg runs from the takeoff point.
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (120.0, 0.0, -22.0), request=start))
    assert t.current.type == SP.SETPOINT_TYPE_POSITION
    assert (t.current.x, t.current.y, t.current.z) == (500.0, 0.0, -40.0)
    assert (t.previous.x, t.previous.y) == (150.0, 0.0)
    assert t.next.valid and (t.next.x, t.next.y) == (500.0, 300.0)
    # The guidance's switching distance (30 m) is shorter than NAV_ACC_RAD: 28 m short of the corner is reached.
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (472.0, 0.0, -40.0), request=start, acceptance_radius=30.0))
    assert (t.current.x, t.current.y) == (500.0, 300.0) and not t.next.valid  # a loiter follows: no turn onto it
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (500.0, 280.0, -40.0), request=start, acceptance_radius=30))
    assert t.current.type == SP.SETPOINT_TYPE_LOITER
    assert t.current.loiter_radius == 70.0 and t.current.loiter_direction_counter_clockwise
    # One full turn about (300, 150) on the 70 m circle, then the return item hands over to the landing.
    for k in range(0, 37):
        a = math.radians(10.0 * k)
        p = (300.0 + 70.0 * math.cos(a), 150.0 - 70.0 * math.sin(a), -40.0)
        t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, p, request=start))
    assert t.current.type == SP.SETPOINT_TYPE_POSITION and (t.current.x, t.current.y) == (0.0, 0.0)  # return home
    assert nav.missions.status().finished


def test_a_mission_uploaded_while_flying_one_starts_over_with_the_new_one() -> None:
    nav = FixedwingNavigator(PARAMS)
    assert nav.missions.load(MISSION, 7, PARAMS) == ""
    start = NavigationRequest(mission_start_counter=1)
    nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (0.0, 0.0, 0.0), landed=True, request=start))
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (120.0, 0.0, -22.0), request=start))
    assert (t.current.x, t.current.y) == (500.0, 0.0) and nav.missions.status().seq_current == 1
    legs = Mission(
        (_item(0, MAV_CMD_NAV_WAYPOINT, -200.0, 100.0, -50.0), _item(1, MAV_CMD_NAV_WAYPOINT, 0.0, 0.0, -50.0))
    )
    for mission_id in (8, 9):  # another mission, then the same one again
        assert nav.missions.load(legs, mission_id, PARAMS) == ""
        t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (300.0, 0.0, -40.0), request=start))
        assert nav.missions.status().seq_current == 0 and nav.missions.status().mission_id == mission_id
        assert (t.current.x, t.current.y) == (-200.0, 100.0) and (t.previous.x, t.previous.y) == (300.0, 0.0)
        t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (-195.0, 100.0, -50.0), request=start))
        assert (t.current.x, t.current.y) == (0.0, 0.0)  # and it flies on
    # A refused upload leaves no mission: the plane circles where it is.
    nav.missions.refuse(10, "unreadable")
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, (310.0, 5.0, -40.0), request=start))
    assert t.current.type == SP.SETPOINT_TYPE_LOITER and (t.current.x, t.current.y) == (310.0, 5.0)


def test_return_flies_home_circles_down_then_lands_along_the_takeoff_runway() -> None:
    nav = FixedwingNavigator(PARAMS)
    nav.update(inputs(NS.NAVIGATION_STATE_AUTO_TAKEOFF, (0.0, 0.0, 0.0), 0.0, landed=True))
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, (400.0, 300.0, -30.0)))
    assert t.current.type == SP.SETPOINT_TYPE_POSITION
    assert (t.current.x, t.current.y, t.current.z) == (0.0, 0.0, -40.0)  # up to RTL_RETURN_ALT on the way
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, (30.0, 20.0, -40.0)))
    assert t.current.type == SP.SETPOINT_TYPE_LOITER and t.current.z == -15.0  # circle down to RTL_DESCEND_ALT
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, (60.0, 0.0, -16.5)))
    back = 15.0 / math.tan(math.radians(5.0)) + APPROACH_STRAIGHT_LOITERS * 60.0
    assert t.current.type == SP.SETPOINT_TYPE_POSITION
    assert (t.current.x, t.current.y, t.current.z) == (pytest.approx(-back), pytest.approx(0.0), -15.0)
    t = nav.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, (-back + 5.0, 3.0, -15.0)))
    assert t.current.type == SP.SETPOINT_TYPE_LAND and (t.current.x, t.current.y, t.current.z) == (0.0, 0.0, 0.0)
    assert t.previous.x == pytest.approx(-back) and t.current.yaw == 0.0
