"""Missions over MAVLink: item conversion both ways, the transfer protocol, and progress for MAVSDK."""

import math

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mathlib.geo import MapProjection
from stack.mavlink.mission_items import ItemRefused, item_from_mission_item_int, mission_item_int
from stack.mavlink.mission_progress import MissionProgress, mission_state
from stack.mavlink.mission_transfer import RETRY_US, Clear, MissionTransfer, Refused, SetCurrent, Upload
from stack.mission.items import GeoPoint, Mission
from stack.mission.transfer import MAX_ITEMS, mission_from_message, mission_message
from stack.msg.navigation import MissionResult
from stack.msg.system import VehicleStatus as NS

OWN = (1, 1)
GCS = (245, 190)
HOME = GeoPoint(47.397742, 8.545594, 488.0)
NAN = math.nan


def _waypoint(seq: int, north: float, east: float, alt: float) -> M.MAVLink_mission_item_int_message:
    lat, lon = MapProjection(HOME.lat, HOME.lon).reproject(north, east)
    return M.MAVLink_mission_item_int_message(
        1, 1, seq, 3, 16, int(seq == 0), 1, 0.0, NAN, 0.0, NAN, round(lat * 1e7), round(lon * 1e7), alt, 0
    )


def _speed(seq: int, speed: float) -> M.MAVLink_mission_item_int_message:
    return M.MAVLink_mission_item_int_message(1, 1, seq, 2, 178, 0, 1, 1.0, speed, -1.0, 0.0, 0, 0, NAN, 0)


def mavsdk_mission() -> list[M.MAVLink_mission_item_int_message]:
    """What MAVSDK uploads for 4 waypoints with a speed: each waypoint followed by DO_CHANGE_SPEED."""
    corners = [(10.0, 0.0), (10.0, 10.0), (0.0, 10.0), (0.0, 0.0)]
    items = []
    for i, (north, east) in enumerate(corners):
        items += [_waypoint(2 * i, north, east, 5.0), _speed(2 * i + 1, 3.0)]
    return items


def test_a_mavsdk_mission_converts_to_local_items_about_home():
    items = [item_from_mission_item_int(m, HOME) for m in mavsdk_mission()]
    assert [i.command for i in items] == [16, 178] * 4
    assert (items[2].north, items[2].east, items[2].down) == pytest.approx((10.0, 10.0, -5.0), abs=0.02)
    assert items[1].speed == 3.0 and items[0].acceptance_radius == 0.0


def test_the_download_gives_back_what_was_uploaded():
    uploaded = mavsdk_mission()
    mission = Mission(tuple(item_from_mission_item_int(m, HOME) for m in uploaded), HOME)
    message = mission_message(mission, HOME, 7)
    home = mission_from_message(message).home
    for seq, (sent, entry) in enumerate(zip(uploaded, message.items, strict=True)):
        back = mission_item_int(entry, seq, home, GCS)
        assert (back.command, back.frame, back.x, back.y, back.seq) == (sent.command, sent.frame, sent.x, sent.y, seq)
        if sent.command == 16:
            assert back.z == sent.z
        else:
            assert (back.param1, back.param2) == (sent.param1, sent.param2)
        assert (back.target_system, back.target_component) == GCS


def test_a_local_item_is_placed_about_the_missions_home():
    mission = Mission((item_from_mission_item_int(_local(0, 30.0, 40.0, -10.0), None),), None)
    entry = mission_message(mission, HOME, 1).items[0]
    back = mission_item_int(entry, 0, HOME, GCS)
    lat, lon = MapProjection(HOME.lat, HOME.lon).reproject(30.0, 40.0)
    assert (back.frame, back.x, back.y, back.z) == (3, round(lat * 1e7), round(lon * 1e7), 10.0)


def _local(seq: int, north: float, east: float, down: float) -> M.MAVLink_mission_item_int_message:
    return M.MAVLink_mission_item_int_message(
        1, 1, seq, 1, 16, 0, 1, 0.0, 0.0, 0.0, NAN, round(north * 1e4), round(east * 1e4), down, 0
    )


@pytest.mark.parametrize(
    ("item", "result", "words"),
    [
        (
            M.MAVLink_mission_item_int_message(1, 1, 0, 3, 177, 0, 1, 1, 2, 0, 0, 0, 0, 0, 0),
            M.MAV_MISSION_UNSUPPORTED,
            "command 177",
        ),
        (
            M.MAVLink_mission_item_int_message(1, 1, 0, 10, 16, 0, 1, 0, 0, 0, 0, 1, 1, 5, 0),
            M.MAV_MISSION_UNSUPPORTED_FRAME,
            "frame 10",
        ),
        (
            M.MAVLink_mission_item_int_message(1, 1, 0, 3, 16, 0, 1, 0, 0, 0, 0, 950000000, 0, 5, 0),
            M.MAV_MISSION_INVALID,
            "latitude 95",
        ),
        (
            M.MAVLink_mission_item_int_message(1, 1, 0, 3, 16, 0, 1, -1, 0, 0, 0, 1, 1, 5, 0),
            M.MAV_MISSION_INVALID,
            "negative",
        ),
        (
            M.MAVLink_mission_item_int_message(1, 1, 0, 3, 16, 0, 1, 0, 0, 0, 0, 1, 1, math.inf, 0),
            M.MAV_MISSION_INVALID,
            "infinite",
        ),
    ],
)
def test_an_item_the_stack_cannot_fly_is_refused_with_the_mission_result_and_why(item, result, words):
    with pytest.raises(ItemRefused) as refused:
        item_from_mission_item_int(item, HOME)
    assert refused.value.mission_result == result and words in str(refused.value)


# -- the transfer --------------------------------------------------------------------------------------------


def _types(out) -> list[str]:
    return [m.get_type() for m in out]


def test_an_upload_requests_each_item_then_acks_after_the_verdict():
    transfer = MissionTransfer(OWN)
    items = mavsdk_mission()
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, len(items), 0), GCS, 0)
    for i, item in enumerate(items):
        out, actions = transfer.take()
        assert [(m.get_type(), m.seq) for m in out] == [("MISSION_REQUEST_INT", i)] and actions == []
        assert (out[0].target_system, out[0].target_component) == GCS
        transfer.on_message(item, GCS, 1000 * i)
    out, actions = transfer.take()
    assert out == [] and actions == [Upload(items)] and transfer.judging
    transfer.verdict(True)
    (ack,) = transfer.take()[0]
    assert (ack.get_type(), ack.type, ack.target_system) == ("MISSION_ACK", M.MAV_MISSION_ACCEPTED, 245)
    assert transfer.uploads == 1 and not transfer.judging


def test_a_missing_item_is_asked_for_again_then_the_upload_is_given_up():
    transfer = MissionTransfer(OWN)
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 2, 0), GCS, 0)
    transfer.take()
    transfer.tick(RETRY_US - 1)
    assert transfer.take()[0] == []
    transfer.tick(RETRY_US)
    assert [(m.get_type(), m.seq) for m in transfer.take()[0]] == [("MISSION_REQUEST_INT", 0)]
    transfer.tick(6_000_000)
    (ack,) = transfer.take()[0]
    assert ack.type == M.MAV_MISSION_OPERATION_CANCELLED


def test_items_out_of_order_a_second_uploader_and_a_refused_verdict():
    transfer = MissionTransfer(OWN)
    items = mavsdk_mission()
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 8, 0), GCS, 0)
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 3, 0), (255, 190), 0)
    out, _ = transfer.take()
    assert [(m.get_type(), getattr(m, "type", None)) for m in out][-1] == ("MISSION_ACK", M.MAV_MISSION_DENIED)
    transfer.on_message(items[0], GCS, 1)
    transfer.on_message(items[0], GCS, 2)  # a repeat: the next one is asked for again
    assert [m.seq for m in transfer.take()[0]] == [1, 1]
    transfer.on_message(items[3], GCS, 3)
    (ack,) = transfer.take()[0]
    assert ack.type == M.MAV_MISSION_INVALID_SEQUENCE
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 1, 0), GCS, 4)
    transfer.on_message(items[0], GCS, 5)
    transfer.verdict(False, M.MAV_MISSION_INVALID)
    assert transfer.take()[0][-1].type == M.MAV_MISSION_INVALID


def test_more_items_than_a_mission_may_have_are_refused_at_the_count_saying_why():
    transfer = MissionTransfer(OWN)
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, MAX_ITEMS + 1, 0), GCS, 0)
    (ack,), actions = transfer.take()
    assert (ack.get_type(), ack.type) == ("MISSION_ACK", M.MAV_MISSION_NO_SPACE) and not transfer.judging
    assert actions == [Refused(f"{MAX_ITEMS + 1} items, more than the {MAX_ITEMS} a mission may have")]
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, MAX_ITEMS, 0), GCS, 1)
    out, actions = transfer.take()
    assert [(m.get_type(), m.seq) for m in out] == [("MISSION_REQUEST_INT", 0)] and actions == []


def test_count_zero_and_clear_all_clear_the_mission():
    transfer = MissionTransfer(OWN)
    transfer.items = [mission_item_int(e, i, HOME, (0, 0)) for i, e in enumerate(_entries())]
    transfer.on_message(M.MAVLink_mission_clear_all_message(1, 1, 0), GCS, 0)
    assert transfer.items == []  # a download right after the clear finds nothing
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 0, 0), GCS, 0)
    transfer.on_message(M.MAVLink_mission_clear_all_message(1, 1, M.MAV_MISSION_TYPE_ALL), GCS, 0)
    out, actions = transfer.take()
    assert actions == [Clear()] * 3 and [m.type for m in out] == [M.MAV_MISSION_ACCEPTED] * 3


def test_a_download_answers_each_request_from_the_vehicles_mission():
    transfer = MissionTransfer(OWN)
    transfer.items = [mission_item_int(e, i, HOME, (0, 0)) for i, e in enumerate(_entries())]
    transfer.on_message(M.MAVLink_mission_request_list_message(1, 1, 0), GCS, 0)
    transfer.on_message(M.MAVLink_mission_request_int_message(1, 1, 1, 0), GCS, 0)
    transfer.on_message(M.MAVLink_mission_request_int_message(1, 1, 9, 0), GCS, 0)
    count, item, bad = transfer.take()[0]
    assert (count.get_type(), count.count) == ("MISSION_COUNT", 8)
    assert (item.get_type(), item.seq, item.target_system, item.target_component) == ("MISSION_ITEM_INT", 1, 245, 190)
    assert bad.type == M.MAV_MISSION_INVALID_SEQUENCE


def _entries():
    mission = Mission(tuple(item_from_mission_item_int(m, HOME) for m in mavsdk_mission()), HOME)
    return mission_message(mission, HOME, 7).items


def test_fence_rally_and_the_float_messages_are_unsupported_and_set_current_is_passed_on():
    transfer = MissionTransfer(OWN)
    transfer.on_message(M.MAVLink_mission_request_list_message(1, 1, M.MAV_MISSION_TYPE_FENCE), GCS, 0)
    transfer.on_message(M.MAVLink_mission_count_message(1, 1, 3, M.MAV_MISSION_TYPE_RALLY), GCS, 0)
    transfer.on_message(M.MAVLink_mission_request_message(1, 1, 0, 0), GCS, 0)
    transfer.on_message(M.MAVLink_mission_set_current_message(1, 1, 3), GCS, 0)
    transfer.on_message(M.MAVLink_mission_request_list_message(7, 1, 0), GCS, 0)  # another vehicle's
    out, actions = transfer.take()
    assert [m.type for m in out] == [M.MAV_MISSION_UNSUPPORTED] * 3
    assert [m.mission_type for m in out] == [M.MAV_MISSION_TYPE_FENCE, M.MAV_MISSION_TYPE_RALLY, 0]
    assert actions == [SetCurrent(3, GCS)]


# -- progress ------------------------------------------------------------------------------------------------


def _result(**fields) -> MissionResult:
    return MissionResult(**{"mission_id": 7, "valid": True, "seq_total": 8, **fields})


@pytest.mark.parametrize(
    ("result", "nav_state", "state"),
    [
        (None, NS.NAVIGATION_STATE_AUTO_MISSION, M.MISSION_STATE_NO_MISSION),
        (_result(valid=False), NS.NAVIGATION_STATE_AUTO_MISSION, M.MISSION_STATE_NO_MISSION),
        (_result(seq_reached=-1), NS.NAVIGATION_STATE_AUTO_LOITER, M.MISSION_STATE_NOT_STARTED),
        (_result(seq_reached=2, seq_current=3), NS.NAVIGATION_STATE_AUTO_MISSION, M.MISSION_STATE_ACTIVE),
        (_result(seq_reached=2, seq_current=3), NS.NAVIGATION_STATE_AUTO_LOITER, M.MISSION_STATE_PAUSED),
        (
            _result(seq_reached=7, seq_current=7, finished=True),
            NS.NAVIGATION_STATE_AUTO_MISSION,
            M.MISSION_STATE_COMPLETE,
        ),
    ],
)
def test_mission_state(result, nav_state, state):
    assert mission_state(result, nav_state) == state


def test_progress_reports_each_item_reached_once_and_the_current_one_on_change():
    progress = MissionProgress()
    out = progress.update(_result(seq_reached=-1, seq_current=0), NS.NAVIGATION_STATE_AUTO_MISSION)
    assert [(m.get_type(), m.seq, m.mission_state) for m in out] == [("MISSION_CURRENT", 0, M.MISSION_STATE_ACTIVE)]
    assert progress.update(_result(seq_reached=-1, seq_current=0), NS.NAVIGATION_STATE_AUTO_MISSION) == []
    out = progress.update(_result(seq_reached=1, seq_current=2), NS.NAVIGATION_STATE_AUTO_MISSION)
    assert [(m.get_type(), m.seq) for m in out] == [
        ("MISSION_ITEM_REACHED", 0),
        ("MISSION_ITEM_REACHED", 1),
        ("MISSION_CURRENT", 2),
    ]
    out = progress.update(_result(seq_reached=7, seq_current=7, finished=True), NS.NAVIGATION_STATE_AUTO_MISSION)
    assert [m.seq for m in out if m.get_type() == "MISSION_ITEM_REACHED"] == [2, 3, 4, 5, 6, 7]
    assert out[-1].mission_state == M.MISSION_STATE_COMPLETE and out[-1].total == 8
    assert progress.current().mission_mode == 1
