import math

import pytest

from stack.mathlib.geo import MapProjection
from stack.mission.items import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    GeoPoint,
    MissionError,
)
from stack.mission.loader import load_mission
from stack.mission.waypoints import parse_waypoint_list, parse_wpl

SIMPLE = """\
# east field
takeoff 5 90           # climb to 5 m
10 0 -5                # bare numbers are a waypoint
waypoint 10 10 -5 - 2 1.5
wp 0 10 -6 180
speed 3
loiter 0 0 -5
land 1 2
rtl
"""


def test_simple_list():
    mission = parse_waypoint_list(SIMPLE, "field.txt")
    assert [i.command for i in mission] == [
        MAV_CMD_NAV_TAKEOFF,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_DO_CHANGE_SPEED,
        MAV_CMD_NAV_LOITER_UNLIM,
        MAV_CMD_NAV_LAND,
        MAV_CMD_NAV_RETURN_TO_LAUNCH,
    ]
    takeoff, wp1, wp2, wp3, speed, loiter, land, rtl = mission
    assert math.isnan(rtl.north)
    assert math.isnan(takeoff.north) and takeoff.down == -5.0 and takeoff.yaw == pytest.approx(math.pi / 2)
    assert wp1.position == (10.0, 0.0, -5.0) and math.isnan(wp1.yaw) and wp1.hold_time == 0.0
    assert (wp2.hold_time, wp2.acceptance_radius) == (2.0, 1.5) and math.isnan(wp2.yaw)
    assert wp3.yaw == pytest.approx(math.pi)
    assert speed.speed == 3.0
    assert loiter.position == (0.0, 0.0, -5.0)
    assert (land.north, land.east) == (1.0, 2.0) and math.isnan(land.down)
    assert [i.index for i in mission] == list(range(8))
    assert mission.home is None and math.isnan(wp1.lat)


def test_simple_list_with_home_gets_latitudes():
    home = GeoPoint(47.0, 8.0, 400.0)
    wp = parse_waypoint_list("10 20 -5\n", home=home)[0]
    assert (wp.lat, wp.lon) == pytest.approx(MapProjection(47.0, 8.0).reproject(10.0, 20.0))
    assert wp.alt == 405.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("10 0\n", "line 1 (item 0): expected north east down [yaw_deg] [hold_s] [radius_m], got 2 value(s)"),
        ("takeoff 5\n10 x -5\n", "line 2 (item 1): east must be a number, got 'x'"),
        ("takeoff -3\n", "takeoff altitude must be above home"),
        ("# c\n\nfly 1 2 3\n", "line 3 (item 0): unknown item 'fly'"),
        ("10 0 -5 0 -1\n", "hold time and acceptance radius must not be negative"),
        ("10 0 inf\n", "down must be finite"),
        ("- 0 -5\n", "north must be given"),
        ("rtl now\n", "expected , got 1 value(s)"),
        ("# nothing\n", "no mission items"),
    ],
)
def test_simple_list_errors(text, message):
    with pytest.raises(MissionError) as error:
        parse_waypoint_list(text, "list.txt")
    assert str(error.value).startswith("list.txt: ")
    assert message in str(error.value)


WPL = (
    "QGC WPL 110\n"
    "0\t1\t0\t16\t0\t0\t0\t0\t47.3977419\t8.5455938\t488.0\t1\n"
    "1\t0\t3\t22\t0\t0\t0\t0\t0\t0\t10.0\t1\n"
    "2\t0\t3\t16\t3\t0\t0\t0\t47.3979215\t8.5455938\t10.0\t1\n"
    "3\t0\t0\t16\t0\t0\t0\t0\t47.3979215\t8.5458592\t500.0\t1\n"
    "4\t0\t2\t20\t0\t0\t0\t0\t0\t0\t0\t1\n"
)


def test_qgc_wpl_110(tmp_path):
    path = tmp_path / "square.waypoints"
    path.write_text(WPL)
    mission = load_mission(path)
    assert mission.home == GeoPoint(47.3977419, 8.5455938, 488.0)
    assert len(mission) == 4
    takeoff, wp1, wp2, rtl = mission
    assert math.isnan(takeoff.north) and takeoff.down == -10.0
    assert wp1.hold_time == 3.0
    assert wp1.position == pytest.approx((19.97, 0.0, -10.0), abs=0.01)
    assert wp2.position == pytest.approx((19.97, 19.97, -12.0), abs=0.01)
    assert rtl.command == MAV_CMD_NAV_RETURN_TO_LAUNCH


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("QGC WPL 100\n", "unsupported version"),
        (WPL.replace("2\t0\t3\t16", "7\t0\t3\t16"), "line 4: sequence number 7, expected 2"),
        (WPL.replace("\t1\n", "\n", 2), "line 2: expected 12 tab-separated fields, got 11"),
        (WPL.replace("3\t0\t0\t16", "3\t0\t4\t16"), "line 5 (item 2): frame 4 is not supported"),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t47\t8\t488\t1\n", "no mission items after the home line"),
    ],
)
def test_wpl_errors(text, message):
    with pytest.raises(MissionError) as error:
        parse_wpl(text, "m.waypoints")
    assert str(error.value).startswith("m.waypoints: ")
    assert message in str(error.value)


def test_loader_picks_the_format_by_content(tmp_path):
    path = tmp_path / "mission.plan"  # the name says plan, the content is a simple list
    path.write_text("takeoff 3\nland\n")
    assert [i.command for i in load_mission(path)] == [MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_LAND]
