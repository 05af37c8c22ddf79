"""The mavlink module's decisions as I/O-free library code: the parameter list's pacing, the mission's home and an
upload's conversion, the download's items, the commands the module answers itself, the view's clearing, the
``telemetry_status`` report and the peer count."""

import math

import pytest
from pymavlink.dialects.v20 import common as M

from stack.commander.state_machine import SUPPORTED_COMMANDS
from stack.mathlib.geo import MapProjection
from stack.mavlink import local_commands
from stack.mavlink.commands import Refusal, from_command
from stack.mavlink.mission_items import ItemRefused, download_items, mission_from_upload, mission_home
from stack.mavlink.param_pacing import PARAM_VALUES_PER_S, ParamPacer, param_rate
from stack.mavlink.presence import PEER_TIMEOUT_US, Presence, telemetry_status
from stack.mavlink.streams import StreamScheduler
from stack.mavlink.telemetry import TELEMETRY_FIELDS, VehicleView
from stack.mission.items import GeoPoint
from stack.mission.transfer import mission_id_for, mission_message
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.system import HomePosition, TelemetryStatus, VehicleStatus
from tests.mavlink.test_missions import HOME, mavsdk_mission

# -- parameter pacing --------------------------------------------------------------------------------------


def test_a_network_link_sends_a_thousand_values_a_second_a_serial_link_half_its_bytes():
    assert param_rate("udp", 0) == param_rate("tcpin", 0) == PARAM_VALUES_PER_S
    assert param_rate("serial", 57600) == pytest.approx(57600 / 10 / 2 / 37)
    assert param_rate("serial", 300) == 1.0  # at least one a second


def test_the_budget_refills_with_time_holds_a_tenth_of_a_second_and_starts_a_list_at_once():
    pacer = ParamPacer(100.0, now_us=0)
    assert pacer.allow(1_000_000, sending=False) == 0
    assert pacer.allow(1_000_000, sending=True) == 1  # the one message kept while idle
    assert pacer.allow(1_050_000, sending=True) == 5
    assert pacer.allow(1_055_000, sending=True) == 0  # half a message owed
    assert pacer.allow(1_060_000, sending=True) == 1
    assert pacer.allow(11_060_000, sending=True) == 10  # a long gap: 0.1 s worth, not 10 s


# -- missions ----------------------------------------------------------------------------------------------


def _home(valid: bool) -> HomePosition:
    return HomePosition(lat=HOME.lat, lon=HOME.lon, alt=HOME.alt, valid_hpos=valid, valid_alt=valid)


def _lpos(x: float, y: float, z: float, valid: bool = True) -> VehicleLocalPosition:
    return VehicleLocalPosition(
        x=x, y=y, z=z, xy_valid=valid, z_valid=valid, ref_lat=HOME.lat, ref_lon=HOME.lon, ref_alt=HOME.alt
    )


def test_the_missions_home_is_the_vehicles_home_else_where_it_is_else_none():
    assert mission_home(_home(True), _lpos(30.0, 40.0, -5.0)) == HOME
    here = mission_home(_home(False), _lpos(30.0, 40.0, -5.0))
    lat, lon = MapProjection(HOME.lat, HOME.lon).reproject(30.0, 40.0)
    assert here == GeoPoint(lat, lon, HOME.alt + 5.0)
    assert mission_home(None, _lpos(1.0, 2.0, 3.0, valid=False)) is None
    no_origin = _lpos(1.0, 2.0, 3.0)
    no_origin.ref_lat = math.nan
    assert mission_home(None, no_origin) is None


def test_an_upload_converts_every_item_about_home_or_refuses_the_first_bad_one():
    mission = mission_from_upload(mavsdk_mission(), HOME, "mavlink:gcs")
    assert (len(mission.items), mission.home, mission.source) == (8, HOME, "mavlink:gcs")
    bad = [*mavsdk_mission(), M.MAVLink_mission_item_int_message(1, 1, 8, 3, 999, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0)]
    with pytest.raises(ItemRefused) as e:
        mission_from_upload(bad, HOME, "mavlink:gcs")
    assert e.value.mission_result == M.MAV_MISSION_UNSUPPORTED


def test_a_download_gets_the_mission_only_once_the_navigator_accepted_that_one():
    mission = mission_from_upload(mavsdk_mission(), HOME, "x")
    msg = mission_message(mission, HOME, mission_id_for(mission))
    accepted = MissionResult(mission_id=msg.mission_id, valid=True, seq_current=2)
    items = download_items(msg, accepted)
    assert [i.seq for i in items] == list(range(8))
    assert [i.current for i in items] == [0, 0, 1, 0, 0, 0, 0, 0]
    assert download_items(msg, MissionResult(mission_id=msg.mission_id, valid=False)) == []
    assert download_items(msg, MissionResult(mission_id=msg.mission_id + 1, valid=True)) == []
    assert download_items(None, accepted) == download_items(msg, None) == []


# -- commands the module answers itself --------------------------------------------------------------------


def test_message_intervals_are_set_and_read_back_bad_arguments_denied_with_the_parameter():
    streams = StreamScheduler()
    att = float(M.MAVLINK_MSG_ID_ATTITUDE)
    assert local_commands.answer(M.MAV_CMD_SET_MESSAGE_INTERVAL, att, 50_000.0, streams, {}) == (0, 0, [])
    result, param, (reply,) = local_commands.answer(M.MAV_CMD_GET_MESSAGE_INTERVAL, att, 0.0, streams, {})
    assert (result, param, reply.message_id, reply.interval_us) == (M.MAV_RESULT_ACCEPTED, 0, 30, 50_000)
    assert local_commands.answer(M.MAV_CMD_SET_MESSAGE_INTERVAL, att, math.nan, streams, {}) == (
        M.MAV_RESULT_DENIED,
        2,
        [],
    )
    assert local_commands.answer(M.MAV_CMD_GET_MESSAGE_INTERVAL, 1.5, 0.0, streams, {}) == (M.MAV_RESULT_DENIED, 1, [])
    assert local_commands.answer(M.MAV_CMD_GET_MESSAGE_INTERVAL, 2.0**24, 0.0, streams, {})[:2] == (
        M.MAV_RESULT_DENIED,
        1,
    )


def test_a_requested_message_is_sent_after_the_ack_unknown_unsupported_no_data_temporarily_rejected():
    ping = M.MAVLink_ping_message(1, 2, 3, 4)
    builders = {M.MAVLINK_MSG_ID_PING: lambda: ping, M.MAVLINK_MSG_ID_VFR_HUD: lambda: None}
    streams = StreamScheduler()

    def ask(command: int, msg_id: float) -> tuple:
        return local_commands.answer(command, msg_id, 0.0, streams, builders)

    assert ask(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_PING) == (M.MAV_RESULT_ACCEPTED, 0, [ping])
    assert ask(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_VFR_HUD) == (M.MAV_RESULT_TEMPORARILY_REJECTED, 0, [])
    assert ask(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_ATTITUDE) == (M.MAV_RESULT_UNSUPPORTED, 0, [])
    assert ask(M.MAV_CMD_REQUEST_MESSAGE, math.inf) == (M.MAV_RESULT_DENIED, 1, [])
    version = M.MAVLink_ping_message(9, 9, 9, 9)
    builders[M.MAVLINK_MSG_ID_AUTOPILOT_VERSION] = lambda: version
    assert ask(M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0.0) == (M.MAV_RESULT_ACCEPTED, 0, [version])
    assert ask(M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0) is None  # the commander's
    assert M.MAV_CMD_COMPONENT_ARM_DISARM not in local_commands.COMMANDS


# -- the view, telemetry_status, peers ---------------------------------------------------------------------


def test_clearing_the_telemetry_keeps_what_the_heartbeat_and_missions_need():
    view = VehicleView(status=VehicleStatus(), home=_home(True), local_position=_lpos(0, 0, 0))
    for field in TELEMETRY_FIELDS:
        assert hasattr(view, field)
    view.clear_telemetry()
    assert view.local_position is None and view.status is not None and view.home is not None


def test_telemetry_status_says_who_is_heard_and_whether_the_link_is_udp():
    status = telemetry_status("udpin", (True, False))
    assert (status.type, status.heartbeat_type_gcs, status.heartbeat_type_onboard_controller) == (
        TelemetryStatus.LINK_TYPE_UDP,
        True,
        False,
    )
    assert telemetry_status("serial", (False, True)).type == 0


def test_peers_count_while_they_sent_anything_lately():
    presence = Presence((1, 1))
    presence.on_message((245, 190), 0)
    presence.on_message((1, 191), 1_000_000)
    assert presence.peer_count(PEER_TIMEOUT_US - 1) == 2
    assert presence.peer_count(PEER_TIMEOUT_US) == 1
    assert presence.peer_count(PEER_TIMEOUT_US + 1_000_000) == 0


def test_a_command_int_above_home_is_placed_with_homes_altitude_only_while_it_is_valid():
    def reposition() -> M.MAVLink_command_int_message:
        frame, command = M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_CMD_DO_REPOSITION
        return M.MAVLink_command_int_message(1, 1, frame, command, 0, 0, -1, 0, 0, 0, 473977420, 85455940, 10)

    cmd = from_command(reposition(), (255, 190), (1, 1), SUPPORTED_COMMANDS, _home(True))
    assert cmd.param7 == HOME.alt + 10 and cmd.param5 == pytest.approx(47.397742)
    refused = from_command(reposition(), (255, 190), (1, 1), SUPPORTED_COMMANDS, _home(False))
    assert isinstance(refused, Refusal) and refused.result == M.MAV_RESULT_DENIED
    arm = M.MAVLink_command_long_message(1, 1, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1.0, 0, 0, 0, 0, 0, 0)
    assert from_command(arm, (255, 190), (1, 1), SUPPORTED_COMMANDS, None).param1 == 1.0
