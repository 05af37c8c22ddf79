"""Mission feasibility: every reason a mission is refused, and what passes."""

from __future__ import annotations

import math

import pytest

from stack.mission.feasibility import mission_problem
from stack.mission.items import (
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_LOCAL_NED,
    Mission,
    MissionItem,
)
from stack.mission.transfer import MAX_ITEMS
from stack.mission.waypoints import parse_waypoint_list

NAN = math.nan
FENCE = {"GF_MAX_HOR_DIST": 100.0, "GF_MAX_VER_DIST": 50.0}


def waypoints(text: str) -> Mission:
    return parse_waypoint_list(text)


def test_a_typical_mission_is_accepted():
    mission = waypoints("takeoff 10\nspeed 4\n50 0 -10 90 2 3\nloiter 50 50 -20\n0 50 -10\nrtl\n")
    assert mission_problem(mission, FENCE) == ""


def test_an_empty_mission_is_refused():
    assert mission_problem(Mission(()), {}) == "the mission has no items"


@pytest.mark.parametrize("position", [(NAN, 0.0, -10.0), (0.0, NAN, -10.0), (10.0, 0.0, NAN), (math.inf, 0.0, -5.0)])
def test_a_waypoint_without_a_usable_position_is_refused(position):
    mission = Mission(
        (
            MissionItem(0, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_LOCAL_NED, 0.0, 0.0, -5.0),
            MissionItem(1, MAV_CMD_NAV_LOITER_TIME, MAV_FRAME_LOCAL_NED, *position, hold_time=5.0),
        )
    )
    assert mission_problem(mission, {}) == "item 1 (loiter_time) has no position"


def test_more_items_than_a_mission_may_have_are_refused():
    longest = waypoints("".join(f"{i % 10} 0 -5\n" for i in range(MAX_ITEMS)))
    assert mission_problem(longest, FENCE) == ""
    longer = waypoints("".join(f"{i % 10} 0 -5\n" for i in range(MAX_ITEMS + 1)))
    assert mission_problem(longer, FENCE) == f"{MAX_ITEMS + 1} items, more than the {MAX_ITEMS} a mission may have"


def test_takeoff_and_land_here_need_no_position():
    assert mission_problem(waypoints("takeoff 5\n10 0 -5\nland\n"), FENCE) == ""


def test_a_waypoint_outside_the_horizontal_geofence_is_refused():
    # 60, 80 → 100.0 m is on the fence (allowed); 60.5, 80 is 100.3 m (outside).
    assert mission_problem(waypoints("60 80 -10\n"), FENCE) == ""
    assert mission_problem(waypoints("0 0 -10\n60.5 80 -10\n"), FENCE) == (
        "item 1 (waypoint) is 100.3 m from home, outside the geofence (GF_MAX_HOR_DIST 100 m)"
    )


def test_a_landing_position_outside_the_geofence_is_refused():
    assert "item 1 (land) is 150.0 m from home, outside the geofence" in mission_problem(
        waypoints("0 0 -10\nland 150 0\n"), FENCE
    )


def test_a_waypoint_above_the_vertical_geofence_is_refused():
    assert mission_problem(waypoints("0 0 -50\n"), FENCE) == ""
    assert mission_problem(waypoints("0 0 -10\n10 0 -50.5\n"), FENCE) == (
        "item 1 (waypoint) is 50.5 m above home, above the geofence (GF_MAX_VER_DIST 50 m)"
    )


def test_a_takeoff_above_the_vertical_geofence_is_refused():
    assert mission_problem(waypoints("takeoff 60\n"), FENCE) == (
        "item 0 (takeoff) is 60.0 m above home, above the geofence (GF_MAX_VER_DIST 50 m)"
    )


def test_below_home_is_never_a_vertical_breach():
    assert mission_problem(waypoints("10 0 80\n"), FENCE) == ""


def test_zero_geofence_limits_disable_the_fence():
    mission = waypoints("500 0 -300\n")
    assert mission_problem(mission, {"GF_MAX_HOR_DIST": 0.0, "GF_MAX_VER_DIST": 0.0}) == ""
    assert mission_problem(mission, {}) == ""  # the fence is off by default


def test_the_first_waypoint_beyond_mis_dist_1wp_is_refused():
    assert mission_problem(waypoints("900 0 -10\n"), {}) == ""
    assert mission_problem(waypoints("takeoff 5\nspeed 3\n600 700 -10\n"), {}) == (
        "item 2 (waypoint) is 922.0 m from home, beyond MIS_DIST_1WP 900 m"
    )
    assert "beyond MIS_DIST_1WP 50 m" in mission_problem(waypoints("60 0 -10\n"), {"MIS_DIST_1WP": 50.0})


def test_mis_dist_1wp_applies_to_the_first_positioned_item_only():
    # The first waypoint is close; the second is far from home but close to the first.
    assert mission_problem(waypoints("500 0 -10\n1000 0 -10\n"), {"MIS_DIST_1WP": 600.0}) == ""


def test_a_leg_longer_than_mis_dist_wps_is_refused():
    mission = waypoints("500 0 -10\nspeed 5\n-500 0 -10\n")
    assert mission_problem(mission, {}) == (
        "item 2 (waypoint) is 1000.0 m from the previous waypoint, beyond MIS_DIST_WPS 900 m"
    )
    assert mission_problem(waypoints("500 0 -10\n-400 0 -10\n"), {}) == ""  # 900 m: on the limit


def test_each_leg_is_measured_from_the_waypoint_before_it():
    assert mission_problem(waypoints("0 0 -10\n800 0 -10\n1600 0 -10\n"), {}) == ""


def test_legs_are_measured_from_the_last_item_with_a_position():
    # The takeoff "here" in between has no horizontal position: the leg is measured 10 → 40 m.
    mission = waypoints("10 0 -10\ntakeoff 5\n40 0 -10\n")
    assert "30.0 m from the previous waypoint" in mission_problem(mission, {"MIS_DIST_WPS": 20.0})


def test_zero_distance_limits_disable_the_sanity_checks():
    mission = waypoints("5000 0 -10\n-5000 0 -10\n")
    assert mission_problem(mission, {"MIS_DIST_1WP": 0.0, "MIS_DIST_WPS": 0.0}) == ""


@pytest.mark.parametrize(("after", "name"), [("10 0 -5", "waypoint"), ("speed 3", "speed"), ("rtl", "rtl")])
def test_any_item_after_a_landing_is_refused(after, name):
    mission = waypoints(f"10 0 -5\nland\n{after}\n")
    assert mission_problem(mission, {}) == f"item 2 ({name}) follows a landing"


def test_a_landing_as_the_last_item_is_accepted():
    land = MissionItem(1, MAV_CMD_NAV_LAND, MAV_FRAME_LOCAL_NED, 20.0, 0.0, NAN)
    mission = Mission((MissionItem(0, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_LOCAL_NED, 0.0, 0.0, -5.0), land))
    assert mission_problem(mission, FENCE) == ""


def test_the_first_problem_in_mission_order_is_reported():
    mission = waypoints("0 0 -60\n200 0 -10\n")  # item 0 too high, item 1 outside
    assert mission_problem(mission, FENCE).startswith("item 0 (waypoint) is 60.0 m above home")
