import math
from pathlib import Path

import msgspec

from stack.mission.items import GeoPoint, Mission, MissionItem
from stack.mission.loader import load_mission
from stack.mission.transfer import mission_from_message, mission_id_for, mission_message
from stack.mission.waypoints import parse_waypoint_list
from stack.msg import navigation

SQUARE = Path(__file__).with_name("data") / "square.plan"
HOME = GeoPoint(47.3977419, 8.5455938, 488.0)
LOCAL = """
takeoff 5 90
10 0 -5 - 2 0.5
speed 3
loiter 0 10 -5
land
rtl
"""


def over_the_wire(msg: navigation.Mission) -> navigation.Mission:
    return msgspec.msgpack.Decoder(navigation.Mission).decode(msgspec.msgpack.encode(msg))


def test_round_trip_is_exact_including_nan_fields():
    # repr compares NaN fields too (NaN != NaN, but its repr is stable), and tells 0.0 from -0.0.
    for mission in (load_mission(SQUARE, HOME), parse_waypoint_list(LOCAL, "local.txt"), load_mission(SQUARE)):
        msg = over_the_wire(mission_message(mission, mission.home, 1234))
        assert msg.mission_id == 1234 and len(msg.items) == len(mission)
        back = mission_from_message(msg)
        assert repr(back) == repr(mission)
        assert [item.index for item in back] == list(range(len(mission)))


def test_message_fields_match_the_items():
    mission = parse_waypoint_list(LOCAL, "local.txt", HOME)
    msg = mission_message(mission, HOME, 7)
    assert (msg.home_lat, msg.home_lon, msg.home_alt, msg.source) == (HOME.lat, HOME.lon, HOME.alt, "local.txt")
    entry, item = msg.items[1], mission[1]
    assert (entry.command, entry.frame, entry.north, entry.east, entry.down) == (16, 1, 10.0, 0.0, -5.0)
    assert (entry.hold_time, entry.acceptance_radius, entry.lat) == (item.hold_time, 0.5, item.lat)
    assert math.isnan(entry.yaw) and math.isfinite(entry.lat)


def test_no_home_travels_as_nan():
    mission = parse_waypoint_list(LOCAL, "local.txt")
    msg = mission_message(mission, None, 1)
    assert math.isnan(msg.home_lat) and math.isnan(msg.home_lon) and math.isnan(msg.home_alt)
    assert mission_from_message(msg).home is None


def test_id_is_stable_31_bit_and_content_sensitive():
    mission = parse_waypoint_list(LOCAL, "local.txt")
    same = parse_waypoint_list(LOCAL, "elsewhere.txt")
    ident = mission_id_for(mission)
    assert ident == mission_id_for(same) == mission_id_for(mission_from_message(mission_message(mission, None, 5)))
    assert 0 < ident < 2**31
    moved = Mission(
        (*mission.items[:1], MissionItem(1, 16, 1, 10.0, 0.0, -5.5, hold_time=2.0), *mission.items[2:]),
        None,
        "local.txt",
    )
    assert mission_id_for(moved) != ident
    assert mission_id_for(Mission(mission.items[:-1])) != ident
    reordered = Mission((mission.items[2], mission.items[1], mission.items[0], *mission.items[3:]))
    assert mission_id_for(reordered) != ident
