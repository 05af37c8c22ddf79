"""LOITER_TURNS and the loiter radius, as a fixed-wing mission needs them: read, written, and sent over MAVLink."""

from __future__ import annotations

import math

import pytest

from stack.launch_files import find_launch_file
from stack.mavlink.mission_items import item_from_mission_item_int, mission_item_int
from stack.mission.items import (
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    GeoPoint,
    item_from_mavlink,
)
from stack.mission.loader import load_mission
from stack.mission.plan import write_plan
from stack.mission.transfer import mission_from_message, mission_message
from stack.sim.simulator import SIH_HOME

HOME = GeoPoint(*SIH_HOME)


def test_loiter_turns_keep_their_turns_and_signed_radius() -> None:
    item = item_from_mavlink(3, MAV_CMD_NAV_LOITER_TURNS, MAV_FRAME_GLOBAL_RELATIVE_ALT,
                             [2.0, 0.0, -70.0, 0.0, HOME.lat, HOME.lon, 40.0], True, HOME)
    assert (item.loiter_turns, item.loiter_radius, item.down) == (2.0, -70.0, -40.0)
    assert math.isnan(item.yaw)
    unlimited = item_from_mavlink(0, MAV_CMD_NAV_LOITER_UNLIM, MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                  [0.0, 0.0, 0.0, math.nan, HOME.lat, HOME.lon, 40.0], True, HOME)
    assert math.isnan(unlimited.loiter_radius)  # 0: the vehicle's NAV_LOITER_RAD
    with pytest.raises(ValueError, match="loiter turns"):
        item_from_mavlink(3, MAV_CMD_NAV_LOITER_TURNS, MAV_FRAME_GLOBAL_RELATIVE_ALT,
                          [0.0, 0.0, 50.0, 0.0, HOME.lat, HOME.lon, 40.0], True, HOME)


def test_the_plane_mission_survives_a_plan_file_the_bus_and_mavlink(tmp_path) -> None:
    mission = load_mission(find_launch_file("missions/plane_rectangle.plan"), HOME)
    loiter = next(item for item in mission if item.command == MAV_CMD_NAV_LOITER_TURNS)
    assert loiter.loiter_turns == 2.0 and (loiter.north, loiter.east) == pytest.approx((325.0, 150.0), abs=0.02)
    write_plan(tmp_path / "again.plan", mission, HOME)
    again = load_mission(tmp_path / "again.plan", HOME)[loiter.index]
    on_bus = mission_from_message(mission_message(mission, HOME, 1))[loiter.index]
    entry = mission_message(mission, HOME, 1).items[loiter.index]
    over_mavlink = item_from_mission_item_int(mission_item_int(entry, loiter.index, HOME, (1, 1)), HOME)
    for copy in (again, on_bus, over_mavlink):
        assert copy.command == MAV_CMD_NAV_LOITER_TURNS and copy.loiter_turns == 2.0
        assert (copy.north, copy.east, copy.down) == pytest.approx((loiter.north, loiter.east, loiter.down), abs=0.02)
