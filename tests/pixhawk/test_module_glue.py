"""The pixhawk module's glue, without a bus or other processes: the real module on a :class:`LinkBench` (topics
fed by hand, publications kept), its real link on 127.0.0.1 UDP talking to a pymavlink stand-in for the Pixhawk
on a port the OS chose. What the Pixhawk's messages publish, what the stack's setpoints send, refusals counted,
status figures, close()."""

from __future__ import annotations

import math
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleRatesSetpoint
from stack.msg.system import ActuatorArmed
from stack.pixhawk import module as pixhawk_module
from stack.pixhawk.module import DEVICE_ID_BASE, PixhawkAdapterModule
from tests.support.link_bench import BusStandIn, LinkBench, wait_for

SYSTEM = 1
ALL_IMU_FIELDS = 0x1FFF


class FakePixhawk:
    """PX4 as the adapter sees it, driven by the test: it sends what it is told and keeps what it receives."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.port: int = self.sock.getsockname()[1]
        self.mav = M.MAVLink(self, srcSystem=SYSTEM, srcComponent=1)
        self.parser = M.MAVLink(None)
        self.adapter: tuple[str, int] | None = None
        self.received: list[Any] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def write(self, data: bytes) -> None:
        assert self.adapter is not None
        self.sock.sendto(data, self.adapter)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                data, self.adapter = self.sock.recvfrom(65536)
            except (TimeoutError, OSError):
                continue
            self.received.extend(self.parser.parse_buffer(data) or [])

    def all(self, kind: str) -> list[Any]:
        return [m for m in list(self.received) if m.get_type() == kind]

    def heartbeat(self, armed: bool = False, mode: Px4Mode = Px4Mode.POSCTL) -> None:
        base = M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (M.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
        state = M.MAV_STATE_ACTIVE if armed else M.MAV_STATE_STANDBY
        self.mav.heartbeat_send(M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4, base, px4_modes.encode(mode), state)

    def imu(self, gyro: tuple[float, float, float], time_usec: int = 1_000_000) -> None:
        self.mav.highres_imu_send(
            time_usec, 0.1, 0.2, -9.8, *gyro, 0.2, 0.0, 0.4, 1000.0, 0.0, 0.0, 20.0, ALL_IMU_FIELDS
        )

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.sock.close()


def _subscription(node: BusStandIn, topic: Any, wake: Any) -> Any:
    return node.add(topic.name, 8, wake)


@pytest.fixture
def pixhawk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[LinkBench, FakePixhawk]]:
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    monkeypatch.setattr(pixhawk_module, "_WakingSubscriber", _subscription)
    fake = FakePixhawk()
    bench = LinkBench(PixhawkAdapterModule, args={"device": f"udpout:127.0.0.1:{fake.port}", "system_id": SYSTEM})
    try:
        wait_for(lambda: fake.all("HEARTBEAT"), what="the adapter's HEARTBEAT")
        fake.heartbeat()
        wait_for(lambda: bench.module.status()["connected"], what="the link up")
        fake.heartbeat()  # PX4's next 1 Hz one: what the Pixhawk does since the link came up
        view = bench.module.handoff.view
        wait_for(lambda: view.heartbeat_us >= view.connected_us > 0, what="a heartbeat since the link came up")
        yield bench, fake
    finally:
        bench.module.close()
        fake.close()


def _run_until(bench: LinkBench, ok: Any, what: str) -> Any:
    """Run the module's 50 Hz step until ``ok()`` (the stream checks, the hand-off and the status are its)."""

    def step() -> Any:
        bench.run(None, 0.02)
        return ok()

    return wait_for(step, what=what)


def test_the_imu_is_published_with_its_values_and_the_streams_asked_for(pixhawk):
    bench, fake = pixhawk
    before = time.monotonic_ns() // 1000
    fake.imu((0.01, -0.02, 0.03))
    (gyro,) = wait_for(lambda: bench.sent(ORB_ID.sensor_gyro), what="the gyro published")
    (accel,) = bench.sent(ORB_ID.sensor_accel)
    assert (gyro.x, gyro.y, gyro.z) == pytest.approx((0.01, -0.02, 0.03))
    assert (accel.x, accel.y, accel.z) == pytest.approx((0.1, 0.2, -9.8))
    assert gyro.device_id == DEVICE_ID_BASE | SYSTEM
    assert before <= gyro.timestamp_sample <= time.monotonic_ns() // 1000  # not synced: the arrival time
    asked = _run_until(
        bench,
        lambda: [c for c in fake.all("COMMAND_LONG") if c.command == M.MAV_CMD_SET_MESSAGE_INTERVAL],
        "the streams asked for",
    )
    assert M.MAVLINK_MSG_ID_HIGHRES_IMU in {int(c.param1) for c in asked}
    assert {(c.target_system, c.target_component) for c in asked} == {(SYSTEM, 1)}
    status = bench.sent(ORB_ID.external_autopilot_status)[-1]
    assert (status.connected, status.system_id, status.autopilot, status.armed) == (True, 1, M.MAV_AUTOPILOT_PX4, False)
    assert status.mode == px4_modes.describe(px4_modes.encode(Px4Mode.POSCTL))


def test_a_gyro_out_of_range_is_refused_and_counted_the_accelerometer_still_published(pixhawk):
    bench, fake = pixhawk
    fake.imu((1e6, 0.0, 0.0))
    wait_for(lambda: bench.sent(ORB_ID.sensor_accel), what="the accelerometer published")
    wait_for(lambda: bench.module.status()["refused"] == 1, what="the gyro refused")
    assert bench.sent(ORB_ID.sensor_gyro) == [] and bench.rejected == 1


def test_disarmed_it_sends_proof_of_life_armed_the_stacks_setpoints_and_never_a_nan_one(pixhawk):
    bench, fake = pixhawk
    idle = _run_until(bench, lambda: fake.all("SET_ATTITUDE_TARGET"), "the idle setpoint")[0]
    assert (idle.thrust, idle.body_roll_rate, idle.target_system) == (0.0, 0.0, SYSTEM)
    setpoint = VehicleRatesSetpoint(roll=0.5, pitch=-0.25, yaw=0.125, thrust_body=(0.0, 0.0, -0.6), timestamp=1)
    bench.node.put(ORB_ID.vehicle_rates_setpoint, setpoint)  # disarmed: not the stack's to send
    (sub,) = bench.node.open(ORB_ID.vehicle_rates_setpoint)
    wait_for(lambda: not sub.queue, what="the link thread taking the setpoint")
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    mode = _run_until(
        bench,
        lambda: [c for c in fake.all("COMMAND_LONG") if c.command == M.MAV_CMD_DO_SET_MODE],
        "OFFBOARD asked for",
    )[0]
    assert (mode.param2, mode.param3) == (Px4Mode.OFFBOARD.main_mode, Px4Mode.OFFBOARD.sub_mode)
    assert bench.sent(ORB_ID.vehicle_thrust_setpoint) == []
    bench.node.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=math.nan, timestamp=2))
    wait_for(lambda: bench.module.status()["refused"] == 1, what="the NaN setpoint refused")
    bench.node.put(ORB_ID.vehicle_rates_setpoint, setpoint)
    (thrust,) = wait_for(lambda: bench.sent(ORB_ID.vehicle_thrust_setpoint), what="the setpoint sent")
    assert thrust.xyz == pytest.approx((0.0, 0.0, -0.6))
    sent = wait_for(lambda: [t for t in fake.all("SET_ATTITUDE_TARGET") if t.thrust > 0], what="it arriving")
    assert (sent[0].body_roll_rate, sent[0].body_pitch_rate, sent[0].body_yaw_rate) == (0.5, -0.25, 0.125)
    assert sent[0].thrust == pytest.approx(0.6) and len(sent) == 1


def test_close_stops_the_link_thread_and_closes_the_link(tmp_path, monkeypatch):
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    monkeypatch.setattr(pixhawk_module, "_WakingSubscriber", _subscription)
    fake = FakePixhawk()
    try:
        bench = LinkBench(PixhawkAdapterModule, args={"device": f"udpout:127.0.0.1:{fake.port}"})
        wait_for(lambda: fake.all("HEARTBEAT"), what="the adapter's HEARTBEAT")
        bench.module.close()
        assert not bench.module._thread.is_alive()
        fd = bench.module.link.fileno()
        assert fd is None or fd == -1
        assert bench.errors == 0 and bench.module.status()["refused"] == 0
    finally:
        fake.close()
