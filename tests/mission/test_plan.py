import json
import math
from pathlib import Path

import pytest

from stack.mission.items import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    GeoPoint,
    MissionError,
)
from stack.mission.loader import load_mission
from stack.mission.plan import parse_plan, plan_json, write_plan
from stack.mission.waypoints import parse_waypoint_list

DATA = Path(__file__).with_name("data")
SQUARE = DATA / "square.plan"
# 1e-7° of latitude/longitude (the plan's rounding) is about 1 cm.
CM = 0.02


def test_real_world_plan_is_read_in_local_ned_about_home():
    mission = load_mission(SQUARE)
    assert mission.home == GeoPoint(47.3977419, 8.5455938, 488.0)
    assert [i.command for i in mission] == [
        MAV_CMD_NAV_TAKEOFF,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_DO_CHANGE_SPEED,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_NAV_RETURN_TO_LAUNCH,
    ]
    takeoff, wp1, speed, wp2, wp3, rtl = mission
    assert takeoff.position == pytest.approx((0.0, 0.0, -15.0), abs=CM)
    assert math.isnan(takeoff.yaw)
    assert wp1.position == pytest.approx((20.0, 0.0, -15.0), abs=CM)
    assert wp1.frame == 3 and wp1.alt == 15.0
    assert speed.speed == 8.0 and not speed.has_position
    assert wp2.position == pytest.approx((20.0, 20.0, -20.0), abs=CM)
    assert (wp2.hold_time, wp2.acceptance_radius) == (5.0, 3.0)
    assert wp2.yaw == pytest.approx(math.pi / 2)
    # Frame 0: AMSL 510 m over a 488 m home is 22 m up.
    assert wp3.frame == 0
    assert wp3.position == pytest.approx((0.0, 20.0, -22.0), abs=CM)
    assert math.isnan(rtl.north) and rtl.index == 5
    assert mission.source == str(SQUARE)


def test_a_given_home_overrides_the_planned_home():
    home = GeoPoint(47.3977419, 8.5455938, 478.0)
    wp3 = load_mission(SQUARE, home=home)[4]
    assert wp3.down == pytest.approx(-32.0)


def _plan(items, home=(47.0, 8.0, 400.0)):
    mission = {"items": items, "version": 2}
    if home is not None:
        mission["plannedHomePosition"] = list(home)
    return json.dumps({"fileType": "Plan", "mission": mission, "version": 1})


def _wp(frame=3, command=16, params=(0, 0, 0, None, 47.0001, 8.0, 10)):
    return {"type": "SimpleItem", "command": command, "frame": frame, "params": list(params), "autoContinue": True}


def test_local_ned_frame():
    mission = parse_plan(_plan([_wp(frame=1, params=(2, 0, 0, 45, 3.0, -4.0, -6.0))]))
    item = mission[0]
    assert item.position == (3.0, -4.0, -6.0)
    assert (item.hold_time, item.yaw) == (2.0, pytest.approx(math.pi / 4))
    assert math.isnan(item.lat)


@pytest.mark.parametrize(
    ("items", "home", "message"),
    [
        (
            [{"type": "ComplexItem", "complexItemType": "survey"}],
            (47, 8, 400),
            "item 0: survey items are not supported",
        ),
        ([_wp(), _wp(frame=10)], (47, 8, 400), "item 1: frame 10 is not supported"),
        ([_wp(command=183)], (47, 8, 400), "item 0: unsupported command 183"),
        ([_wp(params=(0, 0, 0, None, 95.0, 8.0, 10))], (47, 8, 400), "item 0: latitude 95 is outside"),
        ([_wp(params=(0, 0, 0, None, 47.0, 8.0, None))], (47, 8, 400), "item 0: altitude (param 7) must be given"),
        ([_wp(params=(0, -2, 0, None, 47.0, 8.0, 10))], (47, 8, 400), "item 0: acceptance radius -2 m is negative"),
        ([_wp(params=(0, 0, 0, 47.0, 8.0, 10))], (47, 8, 400), "item 0: expected 7 params, got 6"),
        ([_wp(params=(0, 0, 0, "x", 47.0, 8.0, 10))], (47, 8, 400), "item 0: 'x' is not a number"),
        ([_wp(frame=0)], None, "item 0: a global position needs a home position"),
        (
            [{"type": "SimpleItem", "command": "16", "frame": 3, "params": []}],
            (47, 8, 400),
            "item 0: command must be an",
        ),
    ],
)
def test_plan_errors_name_the_file_the_item_and_the_problem(items, home, message):
    with pytest.raises(MissionError) as error:
        parse_plan(_plan(items, home), "flight.plan")
    assert str(error.value).startswith("flight.plan: mission item ")
    assert message in str(error.value)


def test_file_level_errors(tmp_path):
    bad = tmp_path / "bad.plan"
    bad.write_text('{"fileType": "Plan", "mission": {"items": [}')
    with pytest.raises(MissionError, match=r"bad.plan: not valid JSON \(line 1"):
        load_mission(bad)
    other = tmp_path / "other.plan"
    other.write_text('{"fileType": "Fence"}')
    with pytest.raises(MissionError, match="not a QGroundControl plan"):
        load_mission(other)
    with pytest.raises(MissionError, match=r"missing\.plan: cannot read"):
        load_mission(tmp_path / "missing.plan")
    with pytest.raises(MissionError, match="plannedHomePosition must be"):
        parse_plan(_plan([_wp()], home=(47.0, 8.0)))


def test_write_plan_round_trip(tmp_path):
    mission = load_mission(SQUARE)
    out = tmp_path / "copy.plan"
    write_plan(out, mission)
    again = load_mission(out)
    assert again.home == mission.home
    assert len(again) == len(mission)
    for a, b in zip(mission, again, strict=True):
        assert (a.command, a.frame, a.hold_time, a.acceptance_radius, a.autocontinue) == (
            b.command,
            b.frame,
            b.hold_time,
            b.acceptance_radius,
            b.autocontinue,
        )
        assert a.position == pytest.approx(b.position, abs=1e-6, nan_ok=True)
        assert a.yaw == pytest.approx(b.yaw, nan_ok=True)
        assert a.speed == pytest.approx(b.speed, nan_ok=True)
    doc = json.loads(out.read_text())
    assert doc["fileType"] == "Plan" and doc["version"] == 1
    assert doc["mission"]["firmwareType"] == 12 and doc["mission"]["version"] == 2
    assert doc["mission"]["items"][0]["params"][3] is None  # NaN yaw as QGC writes it
    assert [i["doJumpId"] for i in doc["mission"]["items"]] == [1, 2, 3, 4, 5, 6]


def test_local_mission_is_written_in_relative_frame_about_the_home(tmp_path):
    local = parse_waypoint_list("takeoff 5\n30 40 -12 0 1\nland\n")
    home = GeoPoint(47.0, 8.0, 400.0)
    doc = plan_json(local, home)
    wp = doc["mission"]["items"][1]
    assert wp["frame"] == 3 and wp["params"][6] == 12.0 and wp["AltitudeMode"] == 1
    out = tmp_path / "local.plan"
    write_plan(out, local, home)
    again = load_mission(out)
    assert again[1].position == pytest.approx((30.0, 40.0, -12.0), abs=1e-6)
    assert again[0].down == pytest.approx(-5.0)
    with pytest.raises(MissionError, match="needs a home position"):
        plan_json(local)
