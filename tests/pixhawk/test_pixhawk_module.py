"""The pixhawk module as a real process against a plain pymavlink fake Pixhawk on 127.0.0.1 UDP.

The fake streams HIGHRES_IMU with known values, answers TIMESYNC and commands as PX4 does, and mixes garbage
into the link (bytes that are not MAVLink, a frame with a bad checksum, a message id nobody knows). The
module must publish the sensors with their values and mapped sample times, ask for its streams, stream an
idle proof of life while disarmed, hand arming over (OFFBOARD, then arm), forward setpoints and never send a
NaN one, count what it dropped in its heartbeat, and never crash. The test talks to the stack through the
CLI only (no Zenoh session in the test process, which starts processes).
"""

from __future__ import annotations

import contextlib
import json
import math
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from stack.bus.ports import free_port
from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from tests.support.harness import (
    REPO,
    RunningStack,
    eventually,
    run_cli,
    stack_env,
    wait_no_processes,
    write_profile,
)

IMU_HZ = 100.0
GYRO = (0.01, -0.02, 0.03)


class FakePixhawk:
    """PX4 as a companion sees it, just enough: HEARTBEAT, HIGHRES_IMU, TIMESYNC, COMMAND_ACK."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.connect(("127.0.0.1", port))
        self.sock.settimeout(0.005)
        self.mav = mavlink2.MAVLink(self, srcSystem=1, srcComponent=1)
        self.boot = time.monotonic()
        self.armed = False
        self.mode = Px4Mode.POSCTL
        self.commands: list[tuple[int, tuple[float, ...]]] = []
        self.targets: list[tuple[float, int, float, tuple[float, float, float]]] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)

    def write(self, data: bytes) -> None:
        with contextlib.suppress(ConnectionRefusedError):  # the module is not listening yet
            self.sock.send(data)

    def boot_us(self) -> int:
        return int((time.monotonic() - self.boot) * 1e6)

    def run(self) -> None:
        next_imu = next_heartbeat = 0.0
        next_garbage = time.monotonic() + 1.0
        garbage = 0
        parser = mavlink2.MAVLink(None)
        while not self.stop.is_set():
            now = time.monotonic()
            if now >= next_heartbeat:
                next_heartbeat = now + 1.0
                base = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                base |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0
                state = mavlink2.MAV_STATE_ACTIVE if self.armed else mavlink2.MAV_STATE_STANDBY
                self.mav.heartbeat_send(2, 12, base, px4_modes.encode(self.mode), state)
            if now >= next_imu:
                next_imu = now + 1.0 / IMU_HZ
                self.mav.highres_imu_send(self.boot_us(), 0, 0, -9.81, *GYRO, 0.2, 0, 0.4, 1000.0, 0, 0, 20.0, 0x1FFF)
            if now >= next_garbage:  # one kind at a time: damage is counted once per gap between good frames
                next_garbage = now + 0.3
                self.write(self.garbage(garbage))
                garbage += 1
            try:
                data = self.sock.recv(4096)
            except (TimeoutError, ConnectionRefusedError):
                continue
            for msg in parser.parse_buffer(data) or []:
                self.on_message(msg)

    def garbage(self, n: int) -> bytes:
        if n % 3 == 0:
            return b"\x00not mavlink\x01\x02"
        frame = bytearray(self.mav.highres_imu_encode(1, *[0.0] * 13, 0x1FFF).pack(self.mav))
        if n % 3 == 1:
            frame[-1] ^= 0xFF  # checksum
        else:
            frame[7:10] = (60000).to_bytes(3, "little")  # a message id no dialect has
        return bytes(frame)

    def on_message(self, msg: mavlink2.MAVLink_message) -> None:
        kind = msg.get_type()
        if kind == "TIMESYNC" and msg.tc1 == 0:
            self.mav.timesync_send(self.boot_us() * 1000, msg.ts1)
        elif kind == "COMMAND_LONG":
            params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
            self.commands.append((msg.command, params))
            if msg.command == mavlink2.MAV_CMD_DO_SET_MODE:
                self.mode = px4_modes.decode((int(msg.param2) << 16) | (int(msg.param3) << 24)) or self.mode
            elif msg.command == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM:
                self.armed = msg.param1 == 1.0
            sender = (msg.get_srcSystem(), msg.get_srcComponent())
            self.mav.command_ack_send(msg.command, mavlink2.MAV_RESULT_ACCEPTED, 0, 0, *sender)
        elif kind == "SET_ATTITUDE_TARGET":
            rates = (msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate)
            self.targets.append((time.monotonic(), msg.type_mask, msg.thrust, rates))


def echo(home: Path, topic: str) -> dict:
    out = run_cli(home, "topic", "echo", topic, "-n", "1", "--json", "--vehicle", "p1", timeout=60)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def publisher(home: Path, topic: str, payload: dict, rate: float) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "stack",
            "topic",
            "pub",
            topic,
            json.dumps(payload),
            "--rate",
            str(rate),
            "--vehicle",
            "p1",
        ],
        env=stack_env(home),
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def stop(proc: subprocess.Popen) -> None:
    proc.terminate()
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


@pytest.mark.timeout(300)
def test_the_module_against_a_fake_pixhawk(tmp_path: Path) -> None:
    port = free_port(kind=socket.SOCK_DGRAM)
    profile = write_profile(
        tmp_path / "pixhawk_only.toml",
        f"""
[stack]
vehicle = "p1"
lockstep = false
# The test stands in for the modules that would publish these.
open_topics = ["actuator_armed", "vehicle_rates_setpoint"]

[[module]]
module = "pixhawk"
args = {{ device = "udpin:127.0.0.1:{port}" }}
critical = true
""",
    )
    fake = FakePixhawk(port)
    stack = RunningStack(tmp_path, profile)
    pubs: list[subprocess.Popen] = []
    try:
        stack.wait_up()
        fake.thread.start()
        stack.wait_for(r"Pixhawk link up", 60)
        gyro = echo(tmp_path, "sensor_gyro")
        assert (gyro["x"], gyro["y"], gyro["z"]) == pytest.approx(GYRO)
        assert 0 < gyro["timestamp"] - gyro["timestamp_sample"] < 2_000_000  # mapped onto the stack's clock
        baro = echo(tmp_path, "sensor_baro")
        assert baro["pressure"] == pytest.approx(100_000.0)
        # Streams asked for; an idle proof of life while disarmed.
        imu_interval = (mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, 105.0)
        eventually(lambda: any(c[:1] + c[1][:1] == imu_interval for c in fake.commands), 30, "the IMU request")
        eventually(lambda: len(fake.targets) >= 5, 30, "the proof of life")
        assert all(thrust == 0.0 for _, _, thrust, _ in fake.targets)
        status = echo(tmp_path, "external_autopilot_status")
        assert status["connected"] and status["mode"] == "POSCTL" and not status["in_control"]

        # The stack arms: OFFBOARD, then arm; its setpoints are forwarded, a NaN one never.
        pubs.append(publisher(tmp_path, "actuator_armed", {"armed": True}, 5.0))
        eventually(lambda: fake.armed and fake.mode is Px4Mode.OFFBOARD, 60, "OFFBOARD and armed")
        order = [c for c, _ in fake.commands if c != mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL]
        assert order[:2] == [mavlink2.MAV_CMD_DO_SET_MODE, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM]
        nan = {"roll": math.nan, "pitch": 0.0, "yaw": 0.0, "thrust_body": [0.0, 0.0, -0.5]}
        pubs.append(publisher(tmp_path, "vehicle_rates_setpoint", nan, 50.0))
        pubs.append(
            publisher(
                tmp_path,
                "vehicle_rates_setpoint",
                {"roll": 0.1, "pitch": 0.2, "yaw": 0.3, "thrust_body": [0, 0, -0.6]},
                20.0,
            )
        )
        eventually(lambda: any(t[2] == pytest.approx(0.6) for t in fake.targets), 60, "a forwarded setpoint")
        time.sleep(1.0)
        sent = [t for t in fake.targets if t[2] > 0.0]
        assert sent and all(t[1] == 128 and t[3] == pytest.approx((0.1, 0.2, 0.3)) for t in sent)
        assert all(all(math.isfinite(r) for r in t[3]) for t in fake.targets)
        eventually(lambda: echo(tmp_path, "external_autopilot_status")["in_control"], 30, "in control")
        for p in pubs:
            stop(p)
        pubs.clear()
        extra = next(m for m in stack.status()["modules"] if m["module"] == "pixhawk")["extra"]
        assert extra["connected"] and extra["timesync_synced"] and extra["control"] == "in control"
        assert extra["crc_errors"] >= 1 and extra["parse_errors"] >= 1 and extra["unknown_messages"] >= 1
        assert extra["refused"] >= 1  # the NaN setpoints
        assert extra["packets_in"] > 100 and extra["bytes_out"] > 0
    finally:
        for p in pubs:
            stop(p)
        fake.stop.set()
        code = stack.stop()
        fake.thread.join(timeout=5)
        fake.sock.close()
    assert code == 0, stack.output
    assert "Traceback" not in stack.output
    assert not wait_no_processes(tmp_path)


def test_stack_up_device_option_is_checked_before_anything_starts(tmp_path: Path) -> None:
    bad = run_cli(tmp_path, "up", "pixhawk", "--device", "nonsense")
    assert bad.returncode == 2 and "--device: endpoint 'nonsense'" in bad.stderr
    elsewhere = run_cli(tmp_path, "up", "sitl_quad", "--device", "udp:127.0.0.1:14540")
    assert elsewhere.returncode == 2 and "has no pixhawk module" in elsewhere.stderr
    assert not (tmp_path / "runs").exists()
