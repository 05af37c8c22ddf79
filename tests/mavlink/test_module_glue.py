"""The mavlink module's glue, without a bus or other processes: the real module on a :class:`LinkBench` (topics
fed by hand, publications kept), its real link on 127.0.0.1 UDP talking to a pymavlink ground station on a port
the OS chose. What a MAVLink message publishes, what a bus message sends, refusals counted, status, close()."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mavlink import module as mavlink_module
from stack.mavlink.module import MavlinkModule
from stack.msg.navigation import MissionResult
from stack.msg.registry import ORB_ID
from stack.msg.system import HomePosition, MavlinkLog, VehicleCommand, VehicleCommandAck
from stack.params.param import ParamError
from tests.mavlink.peer import VEHICLE, Peer
from tests.mavlink.test_missions import HOME, mavsdk_mission
from tests.support.link_bench import BusStandIn, BusSub, LinkBench, wait_for

PARAMS = [("MPC_XY_VEL_MAX", 12.0, False), ("COM_ARM_WO_GPS", 1, True), ("MC_ROLL_P", 6.5, False)]


class _Subscription:
    """The module's bus subscription, on the bench's stand-in node."""

    def __init__(self, node: BusStandIn, topic: object, capacity: int, wake: object = None) -> None:
        self.topic = topic
        self.sub: BusSub = node.add(topic.name, capacity, wake)  # type: ignore[attr-defined, arg-type]

    def close(self) -> None:
        self.sub.closed = True


class _Params:
    """The parameters the stack's modules would list and set."""

    def __init__(self, session: object, vehicle: str) -> None:
        self.values = {name: value for name, value, _ in PARAMS}

    def list(self) -> list[tuple[str, float | int, bool]]:
        return [(name, self.values[name], is_int) for name, _, is_int in PARAMS]

    def set(self, name: str, value: float) -> float:
        if value < 0:
            raise ParamError("too low")
        self.values[name] = value
        return value


@pytest.fixture
def link(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[LinkBench, Peer]]:
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    monkeypatch.setattr(mavlink_module, "_Subscription", _Subscription)
    monkeypatch.setattr(mavlink_module, "BusParamSource", _Params)
    peer = Peer(0)  # a ground station on a port the OS chose; it answers where the vehicle's HEARTBEAT came from
    port = peer.sock.getsockname()[1]
    bench = LinkBench(MavlinkModule, args={"device": f"udpout:127.0.0.1:{port}", "remote": ""})
    try:
        peer.connect(timeout=5.0)
        wait_for(lambda: bench.module.status()["active"], what="the ground station using the link")
        yield bench, peer
    finally:
        bench.module.close()
        peer.close()


def _acks(peer: Peer, command: int) -> list[int]:
    return [m.result for m in peer.all("COMMAND_ACK") if m.command == command]


def test_a_command_is_published_for_the_commander_and_its_ack_answered_on_the_link(link):
    bench, peer = link
    mark = peer.mark()
    peer.mav.command_long_send(*VEHICLE, M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1.0, 0, 0, 0, 0, 0, 0)
    peer.mav.command_long_send(*VEHICLE, M.MAV_CMD_COMPONENT_ARM_DISARM, 1, 1.0, 0, 0, 0, 0, 0, 0)  # a resend
    (cmd,) = wait_for(lambda: bench.sent(ORB_ID.vehicle_command), what="the command published")
    assert (cmd.command, cmd.param1, cmd.source_system, cmd.source_component) == (400, 1.0, 255, 190)
    assert (cmd.target_system, cmd.target_component) == VEHICLE and cmd.timestamp > 0
    wait_for(lambda: bench.module.status()["command_duplicates"] == 1, what="the resend noticed")
    assert bench.module.status()["pending_commands"] == 1 and not _acks(peer, 400)
    ack = VehicleCommandAck(command=400, result=0, target_system=255, target_component=190, timestamp=1)
    bench.node.put(ORB_ID.vehicle_command_ack, ack)
    assert peer.wait("COMMAND_ACK", lambda m: m.command == 400, timeout=5.0, after=mark).result == 0
    status = bench.module.status()
    assert (status["commands"], status["pending_commands"], len(bench.sent(ORB_ID.vehicle_command))) == (1, 0, 1)


def test_commands_it_answers_itself_or_refuses_publish_nothing(link):
    bench, peer = link
    ack = peer.command(M.MAV_CMD_REQUEST_MESSAGE, float(M.MAVLINK_MSG_ID_AUTOPILOT_VERSION), timeout=5.0)
    assert ack.result == M.MAV_RESULT_ACCEPTED
    peer.wait("AUTOPILOT_VERSION", timeout=5.0)
    assert peer.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, 30.0, math.nan, timeout=5.0).result == M.MAV_RESULT_DENIED
    assert peer.command(31_000, timeout=5.0).result == M.MAV_RESULT_UNSUPPORTED  # no such command
    status = bench.module.status()
    assert (status["unsupported"], status["commands"]) == (1, 0)
    assert bench.sent(ORB_ID.vehicle_command) == []


def test_a_message_for_the_operator_goes_out_as_statustext_a_bad_setpoint_is_counted_refused(link):
    bench, peer = link
    bench.node.put(ORB_ID.mavlink_log, MavlinkLog(severity=4, text="Low battery", timestamp=1))
    text = peer.wait("STATUSTEXT", lambda m: "Low battery" in m.text, timeout=5.0)
    assert text.severity == 4 and bench.module.status()["statustexts"] == 1
    nan = math.nan
    # SET_ATTITUDE_TARGET with a quaternion that is not one: refused, never relayed
    peer.mav.set_attitude_target_send(0, *VEHICLE, 0, [nan, 0, 0, 0], 0, 0, 0, 0.5)
    wait_for(lambda: bench.module.status()["refused"] == 1, what="the setpoint refused")
    assert bench.rejected == 1 and bench.sent(ORB_ID.vehicle_attitude_setpoint) == []


def test_on_the_ground_host_the_link_tells_of_the_commanders_host_lost_and_back(tmp_path, monkeypatch):
    """The commander tells of the other hosts' losses (its mavlink_log); of its own host's, only the link can."""
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    monkeypatch.setattr(mavlink_module, "_Subscription", _Subscription)
    monkeypatch.setattr(mavlink_module, "BusParamSource", _Params)
    placement = {"sim": ["simulator"], "control": ["commander", "mc_rate_control"], "ground": ["mavlink_gcs"]}
    peer = Peer(0)
    port = peer.sock.getsockname()[1]
    bench = LinkBench(
        MavlinkModule,
        args={"device": f"udpout:127.0.0.1:{port}", "remote": ""},
        host="ground",
        placement=placement,
        host_lease_ms=500,
    )
    try:
        peer.connect(timeout=5.0)
        bench.host_beat("sim")
        bench.host_beat("control")
        lost = peer.wait("STATUSTEXT", lambda m: "Lost host control" in m.text, timeout=5.0)
        assert lost.severity == M.MAV_SEVERITY_CRITICAL
        assert lost.text.startswith("Lost host control (no beat for 0.5")
        peer.wait("STATUSTEXT", lambda m: "mc_rate_control" in m.text, timeout=5.0)  # the text's next chunk
        bench.host_beat("control")
        back = peer.wait("STATUSTEXT", lambda m: "Host control back" in m.text, timeout=5.0)
        assert back.severity == M.MAV_SEVERITY_INFO
        assert not [m for m in peer.all("STATUSTEXT") if "sim" in m.text]  # the commander tells of that one
    finally:
        bench.module.close()
        peer.close()


def test_telemetry_status_says_a_ground_station_is_heard(link):
    bench, _ = link
    status = wait_for(lambda: bench.sent(ORB_ID.telemetry_status), what="telemetry_status")[-1]
    assert status.heartbeat_type_gcs and not status.heartbeat_type_onboard_controller
    figures = bench.module.status()
    assert (figures["peers"], figures["gcs"], figures["link_error"]) == (1, True, "")
    assert figures["packets_in"] > 0 and figures["packets_out"] > 0


def test_the_parameter_list_and_a_refused_set(link):
    bench, peer = link
    mark = peer.mark()
    peer.mav.param_request_list_send(*VEHICLE)
    wait_for(lambda: len(peer.all("PARAM_VALUE", after=mark)) >= len(PARAMS), what="the list sent")
    assert sorted(m.param_id for m in peer.all("PARAM_VALUE", after=mark)) == sorted(p[0] for p in PARAMS)
    mark = peer.mark()
    peer.mav.param_set_send(*VEHICLE, b"MPC_XY_VEL_MAX", -1.0, M.MAV_PARAM_TYPE_REAL32)
    peer.wait("STATUSTEXT", lambda m: m.text == "Parameter MPC_XY_VEL_MAX not set: too low", timeout=5.0, after=mark)
    assert bench.module.status()["refused"] == 1


def test_close_stops_the_link_thread_and_withdraws_every_subscription(tmp_path, monkeypatch):
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    monkeypatch.setattr(mavlink_module, "_Subscription", _Subscription)
    monkeypatch.setattr(mavlink_module, "BusParamSource", _Params)
    bench = LinkBench(MavlinkModule, args={"device": "udpout:127.0.0.1:9", "remote": ""})
    subs = [s for subs in bench.node.subs.values() for s in subs]
    assert {t.name for t in mavlink_module.BASE_TOPICS} == set(bench.node.subs)
    bench.module.close()
    assert not bench.module._thread.is_alive() and all(s.closed for s in subs)
    assert bench.module.link.transport is None or bench.module.link.transport.fileno() == -1
    with pytest.raises(RuntimeError, match="link thread"):
        bench.module.run(None, 1.0)
    assert bench.sent(ORB_ID.vehicle_command) == [] and bench.errors == 0
    assert VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM == M.MAV_CMD_COMPONENT_ARM_DISARM


def test_an_upload_is_published_about_home_and_acknowledged_on_the_navigators_verdict(link):
    bench, peer = link
    home = HomePosition(lat=HOME.lat, lon=HOME.lon, alt=HOME.alt, valid_hpos=True, valid_alt=True, timestamp=1)
    bench.node.put(ORB_ID.home_position, home)
    items = mavsdk_mission()
    mark = peer.mark()
    peer.mav.mission_count_send(*VEHICLE, len(items), M.MAV_MISSION_TYPE_MISSION)
    for item in items:
        peer.wait("MISSION_REQUEST_INT", lambda m, seq=item.seq: m.seq == seq, timeout=5.0, after=mark)
        peer.mav.send(item)
    (mission,) = wait_for(lambda: bench.sent(ORB_ID.mission), what="the mission published")
    assert (len(mission.items), mission.home_lat, mission.home_alt) == (len(items), HOME.lat, HOME.alt)
    assert mission.items[2].north == pytest.approx(10.0, abs=0.02)
    assert not peer.all("MISSION_ACK", after=mark)  # the navigator has not judged it yet
    bench.node.put(ORB_ID.mission_result, MissionResult(mission_id=mission.mission_id + 1, valid=True, timestamp=2))
    bench.node.put(ORB_ID.mission_result, MissionResult(mission_id=mission.mission_id, valid=True, timestamp=3))
    ack = peer.wait("MISSION_ACK", timeout=5.0, after=mark)
    assert ack.type == M.MAV_MISSION_ACCEPTED and bench.module.status()["mission_uploads"] == 1
