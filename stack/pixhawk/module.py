"""The ``pixhawk`` plant module: a PX4 Pixhawk over MAVLink in the simulator's place.

The first module of its profile, on the wall clock (never a lockstep member). One thread runs the link:
it waits on the link and on the stack's setpoints, publishes what the Pixhawk streams (its sensors, its
own estimate on instance 1, or 0 with ``estimate = "pixhawk"``, the simulator's truth when there is one)
and sends each new setpoint at once as SET_ATTITUDE_TARGET while the stack is armed. The module's 50 Hz
run does the rest: the arming and Offboard hand-off with the commander, the idle proof-of-life stream,
the stream requests and ``external_autopilot_status``. What it decides is in :mod:`stack.pixhawk.plant`,
how messages map in :mod:`stack.pixhawk.convert`; this file is the glue. Its heartbeat carries the link's
counters, the time sync, and the age of the setpoints it sends (from the gyro sample they were computed
from, through the stack's estimate).
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import select
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import msgspec
from pymavlink.dialects.v20 import common as mavlink2

from stack.bus.topics import TopicSubscriber
from stack.estimator.imu_summary import STATUS_INTERVAL_US, ImuSummary
from stack.mavlink import px4_modes
from stack.mavlink.endpoint import parse_endpoint
from stack.mavlink.link import MavlinkLink, monotonic_us
from stack.msg.estimation import EstimatorStatus
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint
from stack.msg.system import ExternalAutopilotStatus, VehicleCommand, VehicleCommandAck
from stack.msg.topic import Topic
from stack.params import catalogue
from stack.pixhawk import convert, plant
from stack.pixhawk.link_state import (
    MAV_COMP_ID_ONBOARD_COMPUTER,
    Liveness,
    StreamWatch,
    ack_for_adapter,
    external_status,
    sample_us,
)
from stack.runtime.module import Arg, Module, Timer

if TYPE_CHECKING:
    from stack.bus.node import Node
    from stack.runtime.runner import Runtime

RUN_HZ = 50.0
LINK_WAIT_S = 0.02
PROOF_OF_LIFE_US = 100_000
"""The idle setpoint's period (10 Hz: PX4 wants at least 2 Hz, ``docs/en/flight_modes/offboard.md``)."""
STATUS_PERIOD_US = 200_000
SYS_STATUS_BATTERY_AFTER_US = 3_000_000
"""SYS_STATUS gives the battery only if no BATTERY_STATUS came for this long."""
REFUSAL_LOG_EVERY = 500
DEVICE_ID_BASE = 0x4D4C0000
"""Device ids of the Pixhawk's sensors as the stack sees them ("ML" + the MAVLink system id)."""
MODE_COMMANDS = frozenset(
    {
        VehicleCommand.VEHICLE_CMD_DO_SET_MODE,
        VehicleCommand.VEHICLE_CMD_SET_NAV_STATE,
        VehicleCommand.VEHICLE_CMD_NAV_TAKEOFF,
        VehicleCommand.VEHICLE_CMD_NAV_LAND,
        VehicleCommand.VEHICLE_CMD_NAV_RETURN_TO_LAUNCH,
        VehicleCommand.VEHICLE_CMD_NAV_LOITER_UNLIM,
        VehicleCommand.VEHICLE_CMD_DO_REPOSITION,
        VehicleCommand.VEHICLE_CMD_DO_REPOSITION_LOCAL,
        VehicleCommand.VEHICLE_CMD_MISSION_START,
    }
)
"""Commands that set a mode: accepted by the commander after the Pixhawk took over, they hand control back."""
STATUSTEXT_LEVELS = {
    mavlink2.MAV_SEVERITY_EMERGENCY: logging.ERROR,
    mavlink2.MAV_SEVERITY_ALERT: logging.ERROR,
    mavlink2.MAV_SEVERITY_CRITICAL: logging.ERROR,
    mavlink2.MAV_SEVERITY_ERROR: logging.ERROR,
    mavlink2.MAV_SEVERITY_WARNING: logging.WARNING,
    mavlink2.MAV_SEVERITY_NOTICE: logging.INFO,
    mavlink2.MAV_SEVERITY_INFO: logging.INFO,
    mavlink2.MAV_SEVERITY_DEBUG: logging.DEBUG,
}


class _WakingSubscriber(TopicSubscriber):
    """A callback subscription that also wakes the link thread (a byte on a pipe) for each message."""

    __slots__ = ("_wake",)

    def __init__(self, node: Node, topic: Topic, wake: Callable[[], None]) -> None:
        self._wake = wake
        super().__init__(node, topic.name, 0, topic.type, capacity=8, callback=True)
        node.subscribers.append(self)
        node.announce("sub", topic.name, 0)

    def _on_sample(self, sample: Any) -> None:
        TopicSubscriber._on_sample(self, sample)
        self._wake()


ALWAYS_PUBLISHED = (
    ORB_ID.external_autopilot_status,
    ORB_ID.sensor_accel,
    ORB_ID.sensor_gyro,
    ORB_ID.sensor_mag,
    ORB_ID.sensor_baro,
    ORB_ID.sensor_gps,
    ORB_ID.battery_status,
    ORB_ID.sim_groundtruth,
    ORB_ID.vehicle_thrust_setpoint,
)
ESTIMATE = (ORB_ID.vehicle_attitude, ORB_ID.vehicle_local_position)
"""The Pixhawk's estimate: instance 0 when the stack flies on it (PXH_EST_SRC), else 1 beside the stack's own."""
OWN_ESTIMATE_ONLY = (ORB_ID.vehicle_angular_velocity, ORB_ID.vehicle_imu_status, ORB_ID.estimator_status)
"""What the stack's estimators would publish, published instead when it flies on the Pixhawk's estimate."""


class PixhawkAdapterModule(Module):
    NAME = "pixhawk"
    DESCRIPTION = "A PX4 Pixhawk over MAVLink as the plant: its sensors in, the stack's setpoints out in Offboard"
    TRIGGER = Timer(RUN_HZ)
    DT_RANGE = (0.001, 0.1)
    PARAMS = catalogue.params("PXH_EST_SRC", "PXH_SP_TYPE")
    PUBLISHES = (*ALWAYS_PUBLISHED, *ESTIMATE, *OWN_ESTIMATE_ONLY)
    ARGS = (
        Arg("device", "udp:127.0.0.1:14540", "MAVLink endpoint: serial:/dev/ttyACM0:921600, udp:HOST:PORT, tcp:..."),
        Arg("system_id", 1, "MAVLink system id of the vehicle (PX4 MAV_SYS_ID); the adapter is its component 191"),
        Arg("imu_rate_hz", plant.IMU_RATE_HZ, "HIGHRES_IMU rate asked for (less if the serial link cannot carry it)"),
        Arg("link_timeout_s", 3.0, "The link counts as lost after this long without the Pixhawk's heartbeat"),
    )

    def __init__(self, rt: Runtime) -> None:
        super().__init__(rt)
        if rt.spec.lockstep:
            raise ValueError("pixhawk runs on the wall clock: set [stack] lockstep = false in the profile")
        a = self.args
        endpoint = parse_endpoint(str(a["device"]))
        self.own_estimate = bool(self.params["PXH_EST_SRC"])
        attitude_setpoints = bool(self.params["PXH_SP_TYPE"])
        self.estimate_instance = 0 if self.own_estimate else 1
        self.streams = plant.stream_plan(endpoint.baud or None, self.own_estimate, float(a["imu_rate_hz"]))
        self.baud = endpoint.baud or None
        self.subscribe(ORB_ID.actuator_armed)
        self.subscribe(ORB_ID.vehicle_command_ack, queue=True)
        for topic in ALWAYS_PUBLISHED:
            self.advertise(topic)
        for topic in ESTIMATE:
            self.advertise(topic, self.estimate_instance)
        if self.own_estimate:
            for topic in OWN_ESTIMATE_ONLY:
                self.advertise(topic)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._wake_r, self._wake_w = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        setpoint = ORB_ID.vehicle_attitude_setpoint if attitude_setpoints else ORB_ID.vehicle_rates_setpoint
        self.to_target = convert.attitude_target if attitude_setpoints else convert.rates_target
        self.setpoints = _WakingSubscriber(rt.node, setpoint, self._wake)
        self.estimates = rt.node.subscriber(ORB_ID.vehicle_attitude.name, capacity=4, callback=True)
        self.link = MavlinkLink(
            endpoint,
            system_id=int(a["system_id"]),
            component_id=MAV_COMP_ID_ONBOARD_COMPUTER,
            link_timeout_s=float(a["link_timeout_s"]),
            timesync=True,
        )
        self.handoff = plant.Handoff()
        self.truth = convert.TruthFrame()
        self.statustext = convert.StatustextAssembler()
        self.origin = convert.LocalOrigin()
        self.imu = ImuSummary()
        self.latency = plant.LatencyStats()
        self.device_id = DEVICE_ID_BASE | int(a["system_id"])
        self._estimate_sample_us = 0
        self.liveness = Liveness()
        self._last_target_us = 0
        self._battery_status_us = -SYS_STATUS_BATTERY_AFTER_US
        self._status_us = 0
        self._published_status: ExternalAutopilotStatus | None = None
        self._refused = 0
        self.stream_watch = StreamWatch(self.streams)
        self._autopilot: tuple[int, int] | None = None
        self._estimator_status_us = 0
        self.log.info(
            "link %s; asking for HIGHRES_IMU at %.0f Hz; sending %s setpoints; the %s's estimate flies",
            endpoint,
            self.streams[0].hz,
            "attitude" if attitude_setpoints else "body-rate",
            "Pixhawk" if self.own_estimate else "stack",
        )
        self._thread = threading.Thread(target=self._link_loop, name="mavlink", daemon=True)
        self._thread.start()

    # -- the link thread ----------------------------------------------------------------------------------

    def _wake(self) -> None:
        with contextlib.suppress(BlockingIOError):  # a full pipe: a wake is pending already
            os.write(self._wake_w, b"\0")

    def _link_loop(self) -> None:
        while not self._stop.is_set():
            fd = self.link.fileno()
            select.select([self._wake_r] if fd is None else [self._wake_r, fd], [], [], LINK_WAIT_S)
            with contextlib.suppress(BlockingIOError):
                os.read(self._wake_r, 4096)
            try:
                with self._lock:
                    self._service_link()
            except Exception:
                self.rt.errors += 1
                self.log.exception("link thread: a step failed; carrying on")

    def _service_link(self) -> None:
        messages = self.link.poll(0.0)
        now = monotonic_us()
        if messages:
            self.liveness.on_receive(now)
        self.handoff.on_connection(now, self._connected(now))
        for msg in messages:
            self._on_message(msg, now)
        self._track_estimate()
        item = None
        while (newest := self.setpoints.poll()) is not None:
            item = newest
        if item is not None:
            self._forward(item.msg, now)

    def _connected(self, now: int) -> bool:
        """The Pixhawk is heard: data within SILENCE_US, and its heartbeat within the link timeout (counted from
        when data came back after a gap, as the next 1 Hz heartbeat may be a second away)."""
        heard = self._autopilot is not None
        return self.liveness.connected(now, heard, self.link.connected, self.link.link_timeout_us)

    def _track_estimate(self) -> None:
        while (item := self.estimates.poll()) is not None:
            self._estimate_sample_us = item.msg.timestamp_sample

    def _forward(self, setpoint: Any, now: int) -> None:
        """Send the stack's newest setpoint (while it is armed and the link is up); NaN or out of range: refused."""
        if not self.handoff.stream:
            return
        try:
            target = self.to_target(setpoint)
        except convert.Refused as e:
            self._refuse(f"setpoint not sent: {e}")
            return
        self._send_target(target, now)
        self.publish(
            ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(timestamp_sample=now, xyz=(0.0, 0.0, -target.thrust))
        )
        if self._estimate_sample_us:
            self.latency.add(monotonic_us() - self._estimate_sample_us)

    def _send_target(self, t: convert.AttitudeTarget, now: int) -> None:
        peer = self._autopilot or (0, 0)
        self.link.mav.set_attitude_target_send(
            (now // 1000) & 0xFFFFFFFF,
            peer[0],
            peer[1],
            t.type_mask,
            t.q,
            t.body_roll_rate,
            t.body_pitch_rate,
            t.body_yaw_rate,
            t.thrust,
        )
        self._last_target_us = now

    def _refuse(self, why: str) -> None:
        self._refused += 1
        self.rt.rejected += 1
        if self._refused % REFUSAL_LOG_EVERY == 1:
            self.log.warning("%s (%d refused so far)", why, self._refused)

    def _sample_us(self, remote_us: int, now: int) -> int:
        return sample_us(self.link.timesync, remote_us, now)

    def _on_message(self, msg: Any, now: int) -> None:
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if self.link.peer is None or source != self.link.peer:
            return
        kind = msg.get_msgId()
        self.stream_watch.on_message(kind)
        handler = self._handlers.get(kind)
        if handler is None:
            return
        try:
            handler(self, msg, now)
        except convert.Refused as e:
            self._refuse(str(e))

    def _on_heartbeat(self, msg: Any, now: int) -> None:
        if self._autopilot != self.link.peer:
            self._autopilot = self.link.peer
            self.log.info(
                "autopilot: system %d component %d, MAV_AUTOPILOT %d, MAV_TYPE %d, mode %s",
                *self.link.peer,
                msg.autopilot,
                msg.type,
                px4_modes.describe(msg.custom_mode),
            )
        self.handoff.on_heartbeat(now, msg.base_mode, msg.custom_mode, msg.system_status)

    def _on_highres_imu(self, msg: Any, now: int) -> None:
        t = self._sample_us(msg.time_usec, now)
        out, refused = convert.highres_imu(msg, t, self.device_id)
        for why in refused:
            self._refuse(why)
        for topic, m in out:
            self.publish(topic, m)
            if self.own_estimate and topic == ORB_ID.sensor_gyro:
                self._summarise_imu(m, out)

    def _summarise_imu(self, gyro: Any, out: list[tuple[Topic, Any]]) -> None:
        accel = next((m for topic, m in out if topic == ORB_ID.sensor_accel), None)
        self.imu.add(gyro.timestamp_sample, (gyro.x, gyro.y, gyro.z), accel)
        if gyro.timestamp_sample - self.imu.start_us >= STATUS_INTERVAL_US:
            self.publish(ORB_ID.vehicle_imu_status, self.imu.status(gyro))

    def _on_gps(self, msg: Any, now: int) -> None:
        self.publish(ORB_ID.sensor_gps, convert.gps_raw_int(msg, self._sample_us(msg.time_usec, now), self.device_id))

    def _on_battery(self, msg: Any, now: int) -> None:
        self._battery_status_us = now
        self.publish(ORB_ID.battery_status, convert.battery_status(msg))

    def _on_sys_status(self, msg: Any, now: int) -> None:
        self.handoff.on_sys_status(convert.prearm_ok(msg))
        if now - self._battery_status_us > SYS_STATUS_BATTERY_AFTER_US:
            self.publish(ORB_ID.battery_status, convert.sys_status_battery(msg))

    def _on_attitude(self, msg: Any, now: int) -> None:
        t = self._sample_us(msg.time_boot_ms * 1000, now)
        attitude, rates = convert.attitude_quaternion(msg, t)
        if self.own_estimate:
            self.publish(ORB_ID.vehicle_angular_velocity, rates)
        self.publish(ORB_ID.vehicle_attitude, attitude, self.estimate_instance)
        if self.own_estimate and now - self._estimator_status_us >= STATUS_INTERVAL_US:
            self._estimator_status_us = now
            self.publish(
                ORB_ID.estimator_status,
                EstimatorStatus(
                    attitude_valid=True, q=attitude.q, attitude_timestamp=now, angular_velocity_timestamp=now
                ),
            )

    def _on_local_position(self, msg: Any, now: int) -> None:
        lpos = convert.local_position_ned(msg, self._sample_us(msg.time_boot_ms * 1000, now), self.origin)
        self.publish(ORB_ID.vehicle_local_position, lpos, self.estimate_instance)

    def _on_odometry(self, msg: Any, now: int) -> None:
        _, lpos = convert.odometry(msg, self._sample_us(msg.time_usec, now), self.origin)
        self.publish(ORB_ID.vehicle_local_position, lpos, self.estimate_instance)

    def _on_origin(self, msg: Any, now: int) -> None:
        self.origin = convert.gps_global_origin(msg)

    def _on_sim_state(self, msg: Any, now: int) -> None:
        self.publish(ORB_ID.sim_groundtruth, self.truth.convert(msg, now))

    def _on_statustext(self, msg: Any, now: int) -> None:
        text = self.statustext.add(msg.text, getattr(msg, "id", 0), getattr(msg, "chunk_seq", 0))
        if text is None:
            return
        self.handoff.on_statustext(now, msg.severity, text)
        self.log.log(STATUSTEXT_LEVELS.get(msg.severity, logging.INFO), "Pixhawk: %s", text)

    def _on_command_ack(self, msg: Any, now: int) -> None:
        if not ack_for_adapter(msg.target_system, msg.target_component, self.link.system_id):
            return
        self.handoff.on_ack(now, msg.command, msg.result)

    _handlers: ClassVar[dict[int, Callable[[PixhawkAdapterModule, Any, int], None]]] = {
        mavlink2.MAVLINK_MSG_ID_HEARTBEAT: _on_heartbeat,
        mavlink2.MAVLINK_MSG_ID_HIGHRES_IMU: _on_highres_imu,
        mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT: _on_gps,
        mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS: _on_battery,
        mavlink2.MAVLINK_MSG_ID_SYS_STATUS: _on_sys_status,
        mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: _on_attitude,
        mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED: _on_local_position,
        mavlink2.MAVLINK_MSG_ID_ODOMETRY: _on_odometry,
        mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: _on_origin,
        mavlink2.MAVLINK_MSG_ID_SIM_STATE: _on_sim_state,
        mavlink2.MAVLINK_MSG_ID_STATUSTEXT: _on_statustext,
        mavlink2.MAVLINK_MSG_ID_COMMAND_ACK: _on_command_ack,
    }

    # -- the 50 Hz run: hand-off, proof of life, streams, status ----------------------------------------

    def run(self, msg: None, dt: float) -> None:
        armed = self.latest(ORB_ID.actuator_armed)
        mode_set = any(
            ack.command in MODE_COMMANDS and ack.result == VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED
            for ack in self.take(ORB_ID.vehicle_command_ack)
        )
        with self._lock:
            now = monotonic_us()
            h = self.handoff
            h.on_stack_armed(armed is not None and armed.armed)
            if mode_set:
                h.on_stack_mode_command()
            for command in h.tick(now):
                self._send_command(command)
            if h.proof_of_life and now - self._last_target_us >= PROOF_OF_LIFE_US:
                self._send_target(convert.IDLE_TARGET, now)
            self._check_streams(now)
            status = self._status(now)
            events = list(h.events)
            h.events.clear()
        for event in events:
            self.log.info("%s", event)
        if status != self._published_status or now - self._status_us >= STATUS_PERIOD_US:
            self._published_status = status
            self._status_us = now
            self.publish(ORB_ID.external_autopilot_status, status)

    def _send_command(self, c: plant.CommandLong) -> None:
        peer = self._autopilot or (0, 0)
        self.link.mav.command_long_send(peer[0], peer[1], c.command, c.confirmation, *c.params)

    def _check_streams(self, now: int) -> None:
        connected = self.link.connected and self._autopilot is not None
        for command in self.stream_watch.check(now, connected):
            self._send_command(command)

    def _status(self, now: int) -> ExternalAutopilotStatus:
        return external_status(now, self.handoff, self._autopilot, self.link.counters)

    # -- heartbeat figures and shutdown -----------------------------------------------------------------

    def status(self) -> dict[str, float | int | str | bool]:
        with self._lock:
            figures: dict[str, float | int | str | bool] = dict(msgspec.structs.asdict(self.link.counters))
            ts = self.link.timesync
            figures.update(
                connected=self.link.connected,
                control=self.handoff.control.value,
                mode=px4_modes.describe(self.handoff.view.custom_mode),
                timesync_synced=ts.synced,
                timesync_offset_us=ts.offset_us,
                timesync_skew=ts.skew,
                timesync_rtt_us=ts.rtt_us,
                setpoint_age_p50_us=self.latency.percentile(50.0),
                setpoint_age_p99_us=self.latency.percentile(99.0),
                refused=self._refused,
                imu_rate_asked_hz=self.streams[0].hz,
            )
            if self.baud is not None:
                figures["link_budget_bytes_s"] = plant.link_budget_bytes_per_s(self.baud)
        return {k: v for k, v in figures.items() if not (isinstance(v, float) and math.isnan(v))}

    def close(self) -> None:
        self._stop.set()
        self._wake()
        self._thread.join(timeout=2.0)
        with self._lock:
            self.link.close()
        os.close(self._wake_r)
        os.close(self._wake_w)
