import contextlib
import json
import socket
import threading

import pytest
from pymavlink.dialects.v20 import common as mavlink2
from typer.testing import CliRunner

from stack.cli.app import app
from stack.mavlink import px4_modes
from stack.mavlink.framing import FrameParser
from stack.mavlink.inspect import Inspection, NoHeartbeat, firmware, format_summary, inspect_endpoint, mode_name
from stack.mavlink.link import LinkCounters
from tests.support.harness import udp_port

LOITER = px4_modes.encode(px4_modes.Px4Mode.AUTO_LOITER)
ARMED = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED | mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
VERSION_1_14_3 = 1 << 24 | 14 << 16 | 3 << 8 | mavlink2.FIRMWARE_VERSION_TYPE_OFFICIAL
GIT_HASH = bytes.fromhex("0123456789abcdef")


class FakeAutopilot:
    """A tiny PX4-like autopilot on UDP: heartbeats, ATTITUDE at 50 Hz, AUTOPILOT_VERSION on request."""

    def __init__(self, port: int, *, request_message_supported: bool = True) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.connect(("127.0.0.1", port))
        self.sock.settimeout(0.02)
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parser = FrameParser(mavlink2.MAVLink(None))
        self.request_message_supported = request_message_supported
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)

    def __enter__(self) -> "FakeAutopilot":
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()
        self.sock.close()

    def send(self, msg: mavlink2.MAVLink_message) -> None:
        with contextlib.suppress(ConnectionRefusedError):  # the inspector is not listening yet
            self.sock.send(msg.pack(self.mav))
        self.mav.seq = (self.mav.seq + 1) % 256

    def run(self) -> None:
        tick = 0
        while not self.stop.is_set():
            if tick % 10 == 0:
                self.send(
                    self.mav.heartbeat_encode(
                        mavlink2.MAV_TYPE_QUADROTOR,
                        mavlink2.MAV_AUTOPILOT_PX4,
                        ARMED,
                        LOITER,
                        mavlink2.MAV_STATE_ACTIVE,
                    )
                )
            self.send(self.mav.attitude_encode(tick, 0.1, 0.2, 0.3, 0, 0, 0))
            tick += 1
            try:
                data = self.sock.recv(4096)
            except (TimeoutError, ConnectionRefusedError):
                continue
            for msg in self.parser.feed(data):
                if msg.get_type() == "COMMAND_LONG":
                    self.answer(msg)

    def answer(self, command: mavlink2.MAVLink_command_long_message) -> None:
        supported = command.command == mavlink2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES or (
            command.command == mavlink2.MAV_CMD_REQUEST_MESSAGE and self.request_message_supported
        )
        result = mavlink2.MAV_RESULT_ACCEPTED if supported else mavlink2.MAV_RESULT_UNSUPPORTED
        self.send(self.mav.command_ack_encode(command.command, result))
        if supported:
            self.send(
                self.mav.autopilot_version_encode(
                    mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2 | mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT,
                    VERSION_1_14_3,
                    0,
                    0,
                    0,
                    list(GIT_HASH[::-1]),
                    [0] * 8,
                    [0] * 8,
                    0x26AC,
                    0x0011,
                    42,
                )
            )


def received(msg: mavlink2.MAVLink_message, system: int = 1, component: int = 1) -> mavlink2.MAVLink_message:
    mav = mavlink2.MAVLink(None, srcSystem=system, srcComponent=component)
    return FrameParser(mavlink2.MAVLink(None)).feed(msg.pack(mav))[0]


def heartbeat(autopilot: int, base_mode: int, custom_mode: int, mav_type: int = 2) -> mavlink2.MAVLink_message:
    return received(mavlink2.MAVLink_heartbeat_message(mav_type, autopilot, base_mode, custom_mode, 4, 3))


def test_mode_names_for_px4_ardupilot_and_others() -> None:
    assert mode_name(heartbeat(mavlink2.MAV_AUTOPILOT_PX4, ARMED, LOITER)) == "AUTO.LOITER"
    assert mode_name(heartbeat(mavlink2.MAV_AUTOPILOT_PX4, 1, 6 << 16)) == "OFFBOARD"
    assert mode_name(heartbeat(mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, 5)) == "LOITER"
    assert mode_name(heartbeat(mavlink2.MAV_AUTOPILOT_GENERIC, 1, 7)) == "custom mode 7"
    assert mode_name(heartbeat(mavlink2.MAV_AUTOPILOT_PX4, 0x40, 0)) == "base mode 0x40"


def test_firmware_version_decoded() -> None:
    msg = mavlink2.MAVLink_autopilot_version_message(
        mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2,
        1 << 24 | 15 << 16 | 0 << 8 | mavlink2.FIRMWARE_VERSION_TYPE_BETA,
        0,
        0,
        0,
        list(GIT_HASH[::-1]),
        [0] * 8,
        [0] * 8,
        0x26AC,
        0x0011,
        7,
        [0] * 18,
    )
    fw = firmware(received(msg))
    assert fw["version"] == "1.15.0-beta" and fw["git_hash"] == GIT_HASH.hex()
    assert fw["capabilities"] == ["MAVLINK2"]


def test_summary_rates_and_other_components() -> None:
    inspection = Inspection()
    for i in range(11):
        inspection.observe(received(mavlink2.MAVLink_attitude_message(i, 0, 0, 0, 0, 0, 0)), 1_000_000 + i * 20_000)
    inspection.observe(received(mavlink2.MAVLink_heartbeat_message(18, 8, 0, 0, 4, 3), 1, 191), 1_050_000)
    assert inspection.autopilot is None
    with pytest.raises(NoHeartbeat):
        inspection.summary("udpin:127.0.0.1:1", 1_000_000, LinkCounters(), {})
    inspection.observe(heartbeat(mavlink2.MAV_AUTOPILOT_PX4, ARMED, LOITER), 1_100_000)
    summary = inspection.summary("udpin:127.0.0.1:1", 1_000_000, LinkCounters(packets_in=13), {12345: 2})
    assert (summary["system_id"], summary["component_id"], summary["component"]) == (1, 1, "AUTOPILOT1")
    assert (summary["autopilot"], summary["vehicle_type"], summary["system_status"]) == ("PX4", "QUADROTOR", "ACTIVE")
    assert summary["armed"] and summary["mode"] == "AUTO.LOITER" and summary["firmware"] is None
    assert summary["other_components"] == [{"system_id": 1, "component_id": 191, "type": "ONBOARD_CONTROLLER"}]
    rates = {(m["component_id"], m["name"]): m["rate_hz"] for m in summary["messages"]}
    assert rates == {(1, "ATTITUDE"): 50.0, (1, "HEARTBEAT"): 1.0, (191, "HEARTBEAT"): 1.0}  # one in the window
    assert summary["mavlink"] == [2] and summary["unknown_message_ids"] == {"12345": 2}
    text = format_summary(summary)
    assert "ARMED, mode AUTO.LOITER" in text and "no AUTOPILOT_VERSION" in text and "12345 (2)" in text


def test_inspects_a_fake_autopilot_over_udp_as_json() -> None:
    port = udp_port()
    with FakeAutopilot(port):
        result = CliRunner().invoke(app, ["mavlink", "inspect", f"udp:127.0.0.1:{port}", "--seconds", "3", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert (summary["system_id"], summary["autopilot"], summary["vehicle_type"]) == (1, "PX4", "QUADROTOR")
    assert summary["armed"] and summary["mode"] == "AUTO.LOITER"
    assert summary["firmware"]["version"] == "1.14.3-official"
    assert summary["firmware"]["git_hash"] == GIT_HASH.hex()
    assert set(summary["firmware"]["capabilities"]) == {"COMMAND_INT", "MAVLINK2"}
    attitude = next(m for m in summary["messages"] if m["name"] == "ATTITUDE")
    assert attitude["id"] == 30 and 2 < attitude["rate_hz"] < 60  # 50 Hz nominal, slower on a loaded machine
    assert summary["link"]["crc_errors"] == 0 and summary["link"]["packets_out"] >= 1


def test_falls_back_to_request_autopilot_capabilities() -> None:
    port = udp_port()
    with FakeAutopilot(port, request_message_supported=False):
        summary = inspect_endpoint(f"udp:127.0.0.1:{port}", seconds=4.0)
    assert summary["firmware"]["version"] == "1.14.3-official"


def test_exit_codes_without_heartbeat_and_for_a_bad_endpoint() -> None:
    runner = CliRunner()
    silent = runner.invoke(app, ["mavlink", "inspect", f"udp:127.0.0.1:{udp_port()}", "--seconds", "0.5"])
    assert silent.exit_code == 1 and "no autopilot heartbeat" in silent.output and "nothing received" in silent.output
    bad = runner.invoke(app, ["mavlink", "inspect", "serial:"])
    assert bad.exit_code == 2 and "expected serial:DEVICE" in bad.output
