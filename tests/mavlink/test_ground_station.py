"""A ground station on the ``mavlink`` module of a running lockstep stack, played with pymavlink as QGroundControl
plays it: its connect sequence, PX4 mode changes, parameters, missions, takeoff from the ground, refusals, bad
input, signing, a link whose port is taken, the loss of the link in flight (NAV_DLL_ACT) and of the sticks
(NAV_RCL_ACT).

One stack serves the whole file (tests run in order, the later ones fly). The test process opens no Zenoh
session: it reads the stack through the CLI.
"""

from __future__ import annotations

import json
import math
import os
import select
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mavlink import px4_modes
from stack.mavlink.framing import FrameParser
from stack.mavlink.params import decode
from stack.mavlink.px4_modes import Px4Mode
from stack.mission.transfer import MAX_ITEMS
from stack.params import catalogue
from stack.pixhawk.convert import StatustextAssembler
from stack.supervisor.profile import DEFAULT_PROFILE, load_profile
from tests.mavlink.peer import Link, Peer, links_profile, udp_port
from tests.support.harness import RunningStack, eventually, wait_no_processes

KEY = bytes(range(32))
NAN = math.nan
DL_LOSS_T_S = float(catalogue.get("COM_DL_LOSS_T").default)  # the test profile keeps PX4's
RC_LOSS_T_S = float(catalogue.get("COM_RC_LOSS_T").default)


@dataclass
class Vehicle:
    stack: RunningStack
    gcs: Peer
    links: dict[str, Link]
    busy: socket.socket
    radio: int
    """The master side of the pseudo-terminal a serial link (a telemetry radio) is on."""

    def extra(self, module: str) -> dict:
        return next(m for m in self.stack.status()["modules"] if m["module"] == module)["extra"]

    def param(self, name: str) -> str:
        out = self.stack.cli("param", "get", name)
        assert out.returncode == 0, out.stderr
        return out.stdout


@pytest.fixture(scope="module")
def vehicle(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Vehicle]:
    home = tmp_path_factory.mktemp("ground-station")
    (home / "key").write_text(KEY.hex())
    links = {
        "mavlink_gcs": Link("mavlink_gcs", udp_port(), udp_port()),
        "mavlink_signed": Link("mavlink_signed", udp_port(), udp_port(), f', signing_key = "{home / "key"}"'),
        "mavlink_busy": Link("mavlink_busy", udp_port(), udp_port()),
    }
    busy = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)  # someone else has that link's port
    busy.bind(("127.0.0.1", links["mavlink_busy"].local))
    radio, terminal = os.openpty()
    serial = f'device = "serial:{os.ttyname(terminal)}:57600", remote = ""'
    radio_link = f'[[module]]\nname = "mavlink_radio"\nmodule = "mavlink"\nargs = {{ {serial} }}\n'
    os.close(terminal)
    profile = links_profile(home / "gs.toml", list(links.values()))
    profile.write_text(profile.read_text() + radio_link)
    stack = RunningStack(home, profile, "--quiet")
    gcs = Peer(links["mavlink_gcs"].remote)
    try:
        stack.wait_up(120)
        gcs.connect(60)
        yield Vehicle(stack, gcs, links, busy, radio)
    finally:
        gcs.close()
        busy.close()
        code = stack.stop()
        os.close(radio)
    assert code == 0, stack.output
    assert "Traceback" not in stack.output
    assert not wait_no_processes(home)


def signed(msg: M.MAVLink_message) -> bool:
    return bool(msg.get_msgbuf()[2] & M.MAVLINK_IFLAG_SIGNED)  # MAVLink 2 incompat_flags


def texts(peer: Peer, after: int = 0) -> list[str]:
    assembler = StatustextAssembler()
    whole = (assembler.add(m.text, m.id, m.chunk_seq) for m in peer.all("STATUSTEXT", after))
    return [t for t in whole if t is not None]


def wait_text(peer: Peer, start: str, after: int, timeout: float = 10.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = [t for t in texts(peer, after) if t.startswith(start)]
        if found:
            return found[0]
        time.sleep(0.05)
    raise AssertionError(f"no STATUSTEXT '{start}...' within {timeout:g} s; got {texts(peer, after)}")


def wait_mode(peer: Peer, mode: Px4Mode, timeout: float = 20.0, after: int | None = None) -> None:
    """Wait for a HEARTBEAT in ``mode`` received after ``after`` (default: now).

    HEARTBEAT goes out at 1 Hz of wall time: a mode held for less (a lockstep takeoff) may never be in one, so such a
    mode is better seen in the commander's "Mode: ..." STATUSTEXT.
    """
    mark = peer.mark() if after is None else after
    peer.wait(
        "HEARTBEAT", lambda m: m.get_srcComponent() == 1 and px4_modes.decode(m.custom_mode) is mode, timeout, mark
    )


def climbed_above(peer: Peer, metres: float, after: int) -> None:
    """Wait for the vehicle to climb above ``metres`` over home; say what the vehicle said if it does not."""
    try:
        peer.wait("GLOBAL_POSITION_INT", lambda m: m.relative_alt > metres * 1000, 30.0, after)
    except AssertionError as e:
        raise AssertionError(f"{e}; the vehicle said {texts(peer, after)}") from None


def takeoff_amsl(peer: Peer, metres: float) -> float:
    """The altitude ``metres`` above where the vehicle is now, as QGroundControl sends it.

    Not above the first HOME_POSITION: an earlier flight's home may sit below this one's.
    """
    return peer.wait("GLOBAL_POSITION_INT", after=peer.mark()).alt / 1000.0 + metres


def sim_seconds_pass(peer: Peer, seconds: float) -> None:
    """Wait until the vehicle's clock (simulated, in lockstep) has gone ``seconds`` on: ATTITUDE's time_boot_ms."""
    start = peer.wait("ATTITUDE", after=peer.mark()).time_boot_ms
    peer.wait("ATTITUDE", lambda m: m.time_boot_ms >= start + seconds * 1000, timeout=120.0, after=peer.mark())


def prearm_ok(peer: Peer, timeout: float = 30.0) -> None:
    mark = peer.mark()
    peer.wait("SYS_STATUS", lambda m: m.onboard_control_sensors_health & M.MAV_SYS_STATUS_PREARM_CHECK, timeout, mark)


def test_qgroundcontrols_connect_sequence(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    mark = gcs.mark()
    ack = gcs.command(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    assert (ack.result, ack.target_system, ack.target_component) == (M.MAV_RESULT_ACCEPTED, 255, 190)
    version = gcs.wait("AUTOPILOT_VERSION", after=mark)
    for bit in (M.MAV_PROTOCOL_CAPABILITY_MISSION_INT, M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE):
        assert version.capabilities & bit
    assert not version.capabilities & (M.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE | M.MAV_PROTOCOL_CAPABILITY_FTP)
    order = [m.get_type() for _, m in gcs.received[mark:] if m.get_type() in ("COMMAND_ACK", "AUTOPILOT_VERSION")]
    assert order[:2] == ["COMMAND_ACK", "AUTOPILOT_VERSION"]
    for denied in (300, 397, 435):  # PROTOCOL_VERSION, COMPONENT_METADATA, AVAILABLE_MODES
        assert gcs.command(M.MAV_CMD_REQUEST_MESSAGE, denied).result == M.MAV_RESULT_UNSUPPORTED

    mark = gcs.mark()
    gcs.mav.param_request_list_send(1, 0)  # to component 0, as QGroundControl asks
    count = gcs.wait("PARAM_VALUE", after=mark).param_count
    deadline = time.monotonic() + 20.0
    while len(gcs.all("PARAM_VALUE", mark)) < count and time.monotonic() < deadline:
        time.sleep(0.05)
    values = gcs.all("PARAM_VALUE", mark)
    assert count > 200 and len(values) == count
    assert sorted(v.param_index for v in values) == list(range(count)) and {v.param_count for v in values} == {count}
    by_name = {v.param_id: v for v in values}
    assert by_name["NAV_DLL_ACT"].param_type == M.MAV_PARAM_TYPE_INT32
    assert decode(by_name["NAV_DLL_ACT"].param_value, M.MAV_PARAM_TYPE_INT32) == 2  # bytewise, not 2.0
    assert struct.pack("<f", by_name["COM_DL_LOSS_T"].param_value) == struct.pack("<i", 10)
    pos_control = next(m for m in load_profile(DEFAULT_PROFILE).modules if m.name == "mc_pos_control")
    assert by_name["MPC_XY_P"].param_value == pytest.approx(pos_control.params["MPC_XY_P"])

    mark = gcs.mark()
    gcs.mav.mission_request_list_send(1, 1, M.MAV_MISSION_TYPE_MISSION)
    assert gcs.wait("MISSION_COUNT", after=mark).count == 0
    gcs.mav.mission_ack_send(1, 1, M.MAV_MISSION_ACCEPTED, M.MAV_MISSION_TYPE_MISSION)
    home = gcs.wait("HOME_POSITION", timeout=30.0)
    assert home.latitude == pytest.approx(473977420, abs=200)
    prearm_ok(gcs)


def test_px4_mode_changes_by_set_mode_and_do_set_mode(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    mark = gcs.mark()
    gcs.mav.set_mode_send(1, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, px4_modes.encode(Px4Mode.POSCTL))
    wait_mode(gcs, Px4Mode.POSCTL)
    assert wait_text(gcs, "Mode: Position", mark)
    ack = gcs.command(M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 3)
    assert ack.result == M.MAV_RESULT_ACCEPTED
    wait_mode(gcs, Px4Mode.AUTO_LOITER)
    mark = gcs.mark()
    ack = gcs.command(M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 99, 0)
    assert (ack.result, ack.result_param2) == (M.MAV_RESULT_DENIED, 2)
    assert "unknown or unsupported PX4 mode" in wait_text(gcs, "Set mode", mark)


def test_stream_rates_change_on_request(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs

    def rate(seconds: float = 2.0) -> float:
        mark = gcs.mark()
        time.sleep(seconds)
        return len(gcs.all("ATTITUDE", mark)) / seconds

    assert 8.0 <= rate() <= 20.0  # PX4's normal mode: 15 Hz
    assert gcs.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE, 25_000).result == 0
    assert 25.0 <= rate() <= 45.0
    assert gcs.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE, -1).result == 0
    time.sleep(0.2)
    assert rate(1.0) == 0.0
    mark = gcs.mark()
    assert gcs.command(M.MAV_CMD_GET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE).result == 0
    assert gcs.wait("MESSAGE_INTERVAL", after=mark).interval_us == -1
    assert gcs.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_ATTITUDE, 0).result == 0
    assert 8.0 <= rate() <= 20.0
    assert gcs.command(M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAVLINK_MSG_ID_HIGHRES_IMU, 10_000).result == 3
    assert gcs.command(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_HIGHRES_IMU).result == 3


def test_arming_refused_by_the_pre_arm_checks_says_why(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    gps, off, ok = M.FAILURE_UNIT_SENSOR_GPS, M.FAILURE_TYPE_OFF, M.FAILURE_TYPE_OK
    assert gcs.command(M.MAV_CMD_INJECT_FAILURE, gps, off).result == M.MAV_RESULT_ACCEPTED
    mark = gcs.mark()
    gcs.wait("SYS_STATUS", lambda m: not m.onboard_control_sensors_health & M.MAV_SYS_STATUS_PREARM_CHECK, 20, mark)
    mark = gcs.mark()
    ack = gcs.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert ack.result in (M.MAV_RESULT_TEMPORARILY_REJECTED, M.MAV_RESULT_DENIED)
    reason = wait_text(gcs, "Arming denied", mark)
    assert "GPS" in reason or "position" in reason
    assert next(m for m in gcs.all("STATUSTEXT", mark)).severity == M.MAV_SEVERITY_CRITICAL
    assert gcs.command(M.MAV_CMD_INJECT_FAILURE, gps, ok).result == M.MAV_RESULT_ACCEPTED
    prearm_ok(gcs)


def test_bad_input_is_refused_counted_and_changes_nothing(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    before = vehicle.extra("mavlink_gcs")
    frame = bytearray(M.MAVLink_command_long_message(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(gcs.mav))
    frame[-1] ^= 0xFF
    unknown = bytes([0xFD, 4, 0, 0, 7, 255, 190]) + (60_000).to_bytes(3, "little") + b"\x01\x02\x03\x04\x00\x00"
    for damage in (b"\x00not mavlink at all\xff" * 8, bytes(frame), unknown):  # junk, a bad checksum, an unknown id
        gcs.send_raw(damage)
        gcs.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)  # damage counts once per gap
    assert (gcs.command(M.MAV_CMD_COMPONENT_ARM_DISARM, NAN).result, gcs.command(400, math.inf).result) == (2, 2)
    assert gcs.command(M.MAV_CMD_DO_SET_MODE, 1, math.inf).result == M.MAV_RESULT_DENIED
    assert gcs.command(M.MAV_CMD_NAV_TAKEOFF, NAN, NAN, NAN, NAN, NAN, NAN, math.inf).result == M.MAV_RESULT_DENIED
    assert gcs.command(M.MAV_CMD_DO_FLIGHTTERMINATION, 1).result == M.MAV_RESULT_UNSUPPORTED
    mark = gcs.mark()
    gcs.mav.command_int_send(1, 1, M.MAV_FRAME_LOCAL_NED, M.MAV_CMD_DO_REPOSITION, 0, 0, NAN, 1, 0, NAN, 0, 0, 5.0)
    assert gcs.wait("COMMAND_ACK", lambda m: m.command == M.MAV_CMD_DO_REPOSITION, after=mark).result == 2

    mark = gcs.mark()
    gcs.mav.param_set_send(
        1, 1, b"COM_DL_LOSS_T", struct.unpack("<f", struct.pack("<i", 1000))[0], M.MAV_PARAM_TYPE_INT32
    )
    value = gcs.wait("PARAM_VALUE", lambda m: m.param_id == "COM_DL_LOSS_T", after=mark)
    assert decode(value.param_value, value.param_type) == 10
    assert "above the maximum" in wait_text(gcs, "Parameter COM_DL_LOSS_T not set", mark)
    gcs.mav.param_set_send(1, 1, b"MPC_XY_CRUISE", NAN, M.MAV_PARAM_TYPE_REAL32)
    gcs.mav.param_set_send(1, 1, b"MPC_XY_CRUISE", 7.0, M.MAV_PARAM_TYPE_INT32)  # the wrong type
    assert wait_text(gcs, "Parameter MPC_XY_CRUISE not set: nan is not a finite number", mark)
    assert wait_text(gcs, "Parameter MPC_XY_CRUISE not set: it is REAL32", mark)
    gcs.mav.manual_control_send(1, 5000, 0, 500, 0, 0)
    gcs.mav.set_position_target_local_ned_send(0, 1, 1, 1, 0b110111111000, NAN, 0, -5, 0, 0, 0, 0, 0, 0, 0, 0)

    assert gcs.command(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_HOME_POSITION).result == 0  # alive
    assert "COM_DL_LOSS_T = 10" in vehicle.param("COM_DL_LOSS_T")
    assert "MPC_XY_CRUISE = 5.0" in vehicle.param("MPC_XY_CRUISE")
    # The counters are in the module's next heartbeat (about once a second).
    eventually(lambda: vehicle.extra("mavlink_gcs")["refused"] >= before["refused"] + 5, what="the link's counters")
    after = vehicle.extra("mavlink_gcs")
    assert after["parse_errors"] > before["parse_errors"] and after["crc_errors"] > before["crc_errors"]
    assert after["unknown_messages"] > before["unknown_messages"]
    assert after["refused"] >= before["refused"] + 5 and after["handler_errors"] == 0
    status = {m["module"]: m for m in vehicle.stack.status()["modules"]}
    assert status["mavlink_gcs"]["restarts"] == 0 and status["commander"]["state"] == "running"


def test_signing_takes_the_key_and_refuses_the_rest(vehicle: Vehicle) -> None:
    port = vehicle.links["mavlink_signed"].remote
    for key, answered in ((KEY, True), (None, False), (bytes(32), False)):
        peer = Peer(port, key=key)
        try:
            peer.connect()
            if answered:
                ack = peer.command(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
                assert ack.result == M.MAV_RESULT_ACCEPTED and signed(ack)
            else:
                with pytest.raises(AssertionError, match="no COMMAND_ACK"):
                    peer.command(M.MAV_CMD_REQUEST_MESSAGE, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION, timeout=2.0)
            assert signed(peer.wait("HEARTBEAT"))
        finally:
            peer.close()
    eventually(lambda: vehicle.extra("mavlink_signed")["signature_refusals"] >= 2, what="two refusals counted")


def test_a_link_whose_port_is_taken_retries_until_it_is_free(vehicle: Vehicle) -> None:
    extra = vehicle.extra("mavlink_busy")
    assert extra["open_failures"] >= 1 and "in use" in extra["link_error"]
    vehicle.busy.close()
    peer = Peer(vehicle.links["mavlink_busy"].remote)
    try:
        peer.connect(10.0)
    finally:
        peer.close()
    eventually(lambda: vehicle.extra("mavlink_busy")["link_error"] == "", what="the link's error cleared")


def test_a_telemetry_radio_on_a_serial_device(vehicle: Vehicle) -> None:
    mav = M.MAVLink(None, 255, 190)
    parser = FrameParser(M.MAVLink(None, 255, 190))
    received: list[M.MAVLink_message] = []

    def read(until: Callable[[], bool], timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while not until() and time.monotonic() < deadline:
            if select.select([vehicle.radio], [], [], 0.1)[0]:
                received.extend(parser.feed(os.read(vehicle.radio, 4096)))

    read(lambda: any(m.get_type() == "HEARTBEAT" for m in received), 10.0)
    assert any(m.get_type() == "HEARTBEAT" and m.autopilot == M.MAV_AUTOPILOT_PX4 for m in received)
    os.write(vehicle.radio, M.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(mav))
    os.write(vehicle.radio, M.MAVLink_command_long_message(1, 1, 512, 0, 148, 0, 0, 0, 0, 0, 0).pack(mav))
    read(lambda: any(m.get_type() == "AUTOPILOT_VERSION" for m in received), 10.0)
    ack = next(m for m in received if m.get_type() == "COMMAND_ACK")
    assert (ack.command, ack.result) == (512, M.MAV_RESULT_ACCEPTED)
    read(lambda: any(m.get_type() == "SYS_STATUS" for m in received), 10.0)  # streams flow on the radio too


def test_missions_upload_download_refusal_and_clear(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    home = gcs.wait("HOME_POSITION", timeout=10.0)
    items = [
        M.MAVLink_mission_item_int_message(
            1, 1, 0, 3, 16, 1, 1, 0, 0, 0, NAN, home.latitude + 900, home.longitude, 5.0, 0
        ),
        M.MAVLink_mission_item_int_message(1, 1, 1, 2, 178, 0, 1, 1, 4.0, -1, 0, 0, 0, NAN, 0),
        M.MAVLink_mission_item_int_message(1, 1, 2, 3, 16, 0, 1, 0, 0, 0, NAN, home.latitude, home.longitude, 5.0, 0),
    ]

    def upload(mission: list) -> int:
        mark = gcs.mark()
        gcs.mav.mission_count_send(1, 1, len(mission), 0)
        for _ in mission:
            request = gcs.wait("MISSION_REQUEST_INT", after=mark)
            mark = gcs.mark()
            gcs.mav.send(mission[request.seq])
        return gcs.wait("MISSION_ACK", after=mark).type

    assert upload(items) == M.MAV_MISSION_ACCEPTED
    mark = gcs.mark()
    gcs.mav.mission_request_list_send(1, 1, 0)
    assert gcs.wait("MISSION_COUNT", after=mark).count == 3
    for sent in items:
        mark = gcs.mark()
        gcs.mav.mission_request_int_send(1, 1, sent.seq, 0)
        back = gcs.wait("MISSION_ITEM_INT", after=mark)
        assert (back.seq, back.command, back.frame, back.x, back.y) == (
            sent.seq,
            sent.command,
            sent.frame,
            sent.x,
            sent.y,
        )
    gcs.mav.mission_ack_send(1, 1, 0, 0)
    mark = gcs.mark()
    jump = M.MAVLink_mission_item_int_message(1, 1, 0, 2, M.MAV_CMD_DO_JUMP, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0)
    assert upload([jump]) == M.MAV_MISSION_UNSUPPORTED
    assert "command 177 is not supported" in wait_text(gcs, "Mission rejected", mark)
    mark = gcs.mark()
    gcs.mav.mission_clear_all_send(1, 1, 0)
    assert gcs.wait("MISSION_ACK", after=mark).type == M.MAV_MISSION_ACCEPTED
    mark = gcs.mark()
    gcs.mav.mission_request_list_send(1, 1, 0)
    assert gcs.wait("MISSION_COUNT", after=mark).count == 0


def test_a_mission_longer_than_a_mission_may_be_is_refused_at_its_count_saying_why(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    for count in (MAX_ITEMS + 1, 65535):  # 65535: the most MISSION_COUNT can say
        mark = gcs.mark()
        gcs.mav.mission_count_send(1, 1, count, 0)
        assert gcs.wait("MISSION_ACK", after=mark).type == M.MAV_MISSION_NO_SPACE
        text = wait_text(gcs, "Mission rejected", mark)
        assert text == f"Mission rejected: {count} items, more than the {MAX_ITEMS} a mission may have"
        assert gcs.all("MISSION_REQUEST_INT", mark) == []


def test_a_parameter_set_from_a_terminal_is_broadcast(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    mark = gcs.mark()
    assert vehicle.stack.cli("param", "set", "MPC_XY_CRUISE", "7.5").returncode == 0
    value = gcs.wait("PARAM_VALUE", lambda m: m.param_id == "MPC_XY_CRUISE", 15.0, mark)
    assert value.param_value == 7.5 and value.param_type == M.MAV_PARAM_TYPE_REAL32
    assert vehicle.stack.cli("param", "set", "MPC_XY_CRUISE", "5.0").returncode == 0


def _stream(gcs: Peer, send: Callable[[], None], hz: float) -> tuple[threading.Event, threading.Thread]:
    stop = threading.Event()

    def run() -> None:
        while not stop.wait(1.0 / hz):
            send()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return stop, thread


def test_sticks_reach_manual_control_setpoint_and_their_loss_is_noticed(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    stop, thread = _stream(gcs, lambda: gcs.mav.manual_control_send(1, 250, -500, 750, 100, 0), 20.0)
    try:
        out = vehicle.stack.cli("topic", "echo", "manual_control_setpoint", "-n", "1", "--json")
        mark = gcs.mark()
    finally:
        stop.set()
        thread.join()
    assert wait_text(gcs, "Manual control lost", mark)  # on the ground, disarmed: noticed, no failsafe
    assert out.returncode == 0, out.stderr
    sticks = json.loads(out.stdout.splitlines()[0])
    assert (sticks["pitch"], sticks["roll"], sticks["throttle"], sticks["yaw"]) == (0.25, -0.5, 0.5, 0.1)
    assert sticks["valid"]


def test_qgroundcontrols_takeoff_from_the_ground_then_link_loss_returns(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    prearm_ok(gcs)
    altitude = takeoff_amsl(gcs, 3.0)
    before = gcs.mark()
    ack = gcs.command(M.MAV_CMD_NAV_TAKEOFF, -1, 0, 0, NAN, NAN, NAN, altitude)  # as QGC sends it
    assert ack.result == M.MAV_RESULT_ACCEPTED
    assert wait_text(gcs, "Mode: Takeoff", before)  # over within a wall second: maybe in no HEARTBEAT
    assert gcs.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED  # then QGC arms
    climbed_above(gcs, 2.5, gcs.mark())
    wait_mode(gcs, Px4Mode.AUTO_LOITER)

    here = gcs.wait("LOCAL_POSITION_NED", after=gcs.mark())
    target = (here.x + 4.0, here.y, here.z)  # offboard: 4 m north, streamed at 10 Hz, PX4's proof of life
    position_only = 0b110111111000
    stop, thread = _stream(
        gcs, lambda: gcs.mav.set_position_target_local_ned_send(0, 1, 1, 1, position_only, *target, *[0.0] * 8), 10.0
    )
    try:
        heard = vehicle.stack.cli("topic", "echo", "offboard_control_mode", "-n", "1", "--json")  # the proof of life
        assert heard.returncode == 0, heard.stderr
        assert gcs.command(M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 6, 0).result == 0
        wait_mode(gcs, Px4Mode.OFFBOARD)
        mark = gcs.mark()
        gcs.wait("LOCAL_POSITION_NED", lambda m: abs(m.x - target[0]) < 0.5, 30.0, mark)
        assert gcs.command(M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 3).result == 0
        wait_mode(gcs, Px4Mode.AUTO_LOITER)
    finally:
        stop.set()
        thread.join()

    sim_seconds_pass(gcs, 2 * DL_LOSS_T_S)  # beyond COM_DL_LOSS_T: a ground station heard at 1 Hz is not lost
    assert px4_modes.decode(gcs.mode()) is Px4Mode.AUTO_LOITER
    mark = gcs.mark()
    gcs.heartbeats = False  # the ground station goes silent: NAV_DLL_ACT = 2 (Return) after COM_DL_LOSS_T
    try:
        wait_mode(gcs, Px4Mode.AUTO_RTL, timeout=30.0, after=mark)
    finally:
        gcs.heartbeats = True
    assert wait_text(gcs, "Connection to ground station lost", mark)
    assert "gcs_connection_loss" in wait_text(gcs, "Failsafe activated", mark)
    mark = gcs.mark()
    gcs.wait("HEARTBEAT", lambda m: not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED, 60.0, mark)
    assert vehicle.extra("mavlink_gcs")["handler_errors"] == 0


def test_sticks_stopping_in_flight_are_the_manual_control_loss_failsafe(vehicle: Vehicle) -> None:
    gcs = vehicle.gcs
    start = gcs.mark()
    prearm_ok(gcs)
    stop, thread = _stream(gcs, lambda: gcs.mav.manual_control_send(1, 0, 0, 500, 0, 0), 20.0)  # centred sticks
    try:
        heard = vehicle.stack.cli("topic", "echo", "manual_control_setpoint", "-n", "1", "--json")
        assert heard.returncode == 0, heard.stderr
        ack = gcs.command(M.MAV_CMD_NAV_TAKEOFF, -1, 0, 0, NAN, NAN, NAN, takeoff_amsl(gcs, 3.0))
        assert ack.result == M.MAV_RESULT_ACCEPTED
        assert gcs.command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        climbed_above(gcs, 2.5, start)
        wait_mode(gcs, Px4Mode.AUTO_LOITER)
        sim_seconds_pass(gcs, 20 * RC_LOSS_T_S)  # 20 Hz sticks are never taken as lost, however fast time runs
        assert px4_modes.decode(gcs.mode()) is Px4Mode.AUTO_LOITER, texts(gcs, start)
        mark = gcs.mark()
    finally:
        stop.set()
        thread.join()
    wait_mode(gcs, Px4Mode.AUTO_RTL, timeout=30.0, after=mark)  # NAV_RCL_ACT = 2 (Return), PX4's default
    assert wait_text(gcs, "Manual control lost", mark)
    assert "manual_control_loss" in wait_text(gcs, "Failsafe activated", mark)
    gcs.wait("HEARTBEAT", lambda m: not m.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED, 60.0, gcs.mark())


def test_the_fast_path_modules_saw_no_outside_triggers(vehicle: Vehicle) -> None:
    status = {m["module"]: m for m in vehicle.stack.status()["modules"]}
    for module in ("mc_pos_control", "mc_hover_thrust_estimator"):  # triggered by a topic the links read
        assert status[module]["rejected"] == 0, module


def test_the_busy_links_log_says_what_happened(vehicle: Vehicle) -> None:
    run_dir = vehicle.stack.run_dir()
    log = (Path(run_dir) / "mavlink_busy.log").read_text()
    assert "in use" in log and "open" in log
