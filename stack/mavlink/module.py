"""The ``mavlink`` module: one MAVLink link to ground stations and SDKs, the stack answering as a PX4 autopilot.

One process per link, as PX4 starts one ``mavlink`` instance per port. A thread serves the link: it waits on the
link and on a wake-up pipe (an acknowledgement from the commander wakes it at once), reads what came, publishes
what it asks for, and sends what is due; the protocols are the I/O-free classes of :mod:`stack.mavlink`, this file is
the glue. The module never joins the lockstep (``OUTSIDE_LOCKSTEP``): it runs on the wall clock, streams at wall
rates, judges its peers' liveness on the wall clock, and stamps what it publishes with the latest simulated time
it has seen (:mod:`stack.mavlink.clock`).

It reads the topics behind the telemetry only while a peer is using the link (a message within the last
PEER_TIMEOUT_US): until then it sends its HEARTBEAT and reads the few topics that say what the vehicle is doing, so
an idle link costs the stack (and its lockstep) next to nothing. Parameter queries go through a worker thread, as
they wait for every module's answer. Its heartbeat carries the link's counters and what it forwarded, answered,
refused and dropped.
"""

from __future__ import annotations

import contextlib
import math
import os
import queue
import select
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any, ClassVar

from pymavlink.dialects.v20 import common as mavlink2

from stack.bus import keys
from stack.bus.host_beats import HostWatch
from stack.bus.node import wall_clock_us
from stack.bus.topics import TopicSubscriber
from stack.commander.module import CommanderModule
from stack.commander.state_machine import SUPPORTED_COMMANDS
from stack.mavlink import (
    commands,
    identity,
    local_commands,
    mission_items,
    offboard,
    params,
    signing,
    telemetry,
    transport,
)
from stack.mavlink.clock import StampClock
from stack.mavlink.endpoint import Endpoint, parse_endpoint
from stack.mavlink.link import MavlinkLink
from stack.mavlink.manual import ManualInput, manual_control
from stack.mavlink.mission_progress import MissionProgress
from stack.mavlink.mission_transfer import Clear, MissionTransfer, Refused, SetCurrent, Upload
from stack.mavlink.param_pacing import ParamPacer, param_rate
from stack.mavlink.param_source import BusParamSource
from stack.mavlink.presence import Presence, telemetry_status
from stack.mavlink.statustext import StatustextSender
from stack.mavlink.streams import StreamScheduler
from stack.mission.items import Mission
from stack.mission.transfer import mission_id_for, mission_message
from stack.msg.navigation import Mission as MissionMsg
from stack.msg.navigation import MissionResult
from stack.msg.registry import ORB_ID, fingerprint
from stack.msg.system import VehicleCommand, VehicleCommandAck
from stack.msg.system import VehicleStatus as NS
from stack.msg.topic import Topic
from stack.params import catalogue
from stack.params.param import ParamError
from stack.runtime.module import Arg, Module, Timer
from stack.runtime.spec import ModuleSpec

if TYPE_CHECKING:
    from stack.bus.node import Node
    from stack.runtime.runner import Runtime

ACTIVE_WAIT_S = 0.01
IDLE_WAIT_S = 0.1
ACK_TIMEOUT_US = 3_000_000
"""A command the commander has not answered in this long is answered FAILED."""
ERROR_LOG_EVERY = 100
BASE_TOPICS = (
    ORB_ID.vehicle_status,
    ORB_ID.vehicle_control_mode,
    ORB_ID.vehicle_land_detected,
    ORB_ID.home_position,
    ORB_ID.vehicle_command_ack,
    ORB_ID.mavlink_log,
    ORB_ID.parameter_update,
    ORB_ID.mission,
    ORB_ID.mission_result,
)
"""Read always: what the HEARTBEAT, the acknowledgements, the operator's messages and the missions need."""
TELEMETRY_TOPICS = (
    ORB_ID.vehicle_local_position,
    ORB_ID.estimator_status,
    ORB_ID.vehicle_imu_status,
    ORB_ID.sensor_gps,
    ORB_ID.battery_status,
    ORB_ID.sensor_mag,
    ORB_ID.sensor_baro,
)
"""Read while a peer uses the link."""
VIEW_FIELDS = {
    ORB_ID.vehicle_status: "status",
    ORB_ID.vehicle_control_mode: "control_mode",
    ORB_ID.vehicle_land_detected: "land",
    ORB_ID.home_position: "home",
    ORB_ID.vehicle_local_position: "local_position",
    ORB_ID.estimator_status: "estimator",
    ORB_ID.vehicle_imu_status: "imu",
    ORB_ID.sensor_gps: "gps",
    ORB_ID.battery_status: "battery",
    ORB_ID.sensor_mag: "mag",
    ORB_ID.sensor_baro: "baro",
}
QUEUED_TOPICS = {ORB_ID.vehicle_command_ack: 64, ORB_ID.mavlink_log: 64, ORB_ID.mission: 8, ORB_ID.mission_result: 16}
M = mavlink2


class _Subscriber(TopicSubscriber):
    """Decoded on Zenoh's thread into a queue; optionally wakes the link thread for each message."""

    __slots__ = ("_wake",)

    def __init__(self, node: Node, topic: Topic, capacity: int, wake: Callable[[], None] | None) -> None:
        self._wake = wake
        super().__init__(node, topic.name, 0, topic.type, capacity, callback=True)

    def _on_sample(self, sample: Any) -> None:
        TopicSubscriber._on_sample(self, sample)
        if self._wake is not None:
            self._wake()


class _Subscription:
    """A subscription this module declares and withdraws while it runs, announced in the topic graph (so that a
    fast-path run puts the topic on Zenoh for it only while it is there)."""

    def __init__(self, node: Node, topic: Topic, capacity: int, wake: Callable[[], None] | None = None) -> None:
        self.topic = topic
        self.sub = _Subscriber(node, topic, capacity, wake)
        kind = topic.type
        key = keys.graph_token(node.vehicle, node.name, "sub", topic.name, 0, kind.__name__, fingerprint(kind))
        self.token = node.session.liveliness().declare_token(key)

    def close(self) -> None:
        self.token.undeclare()
        self.sub.undeclare()


def _open(remote: tuple[str, int] | None) -> Callable[[Endpoint], transport.Transport]:
    def opener(endpoint: Endpoint) -> transport.Transport:
        if endpoint.kind == "udpin":
            return transport.UdpPeerTransport(endpoint.host, endpoint.port, remote)
        return transport.open_transport(endpoint)

    return opener


def _remote(text: str) -> tuple[str, int] | None:
    if not text:
        return None
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"remote {text!r}: expected HOST:PORT, e.g. 127.0.0.1:14550")
    return host, int(port)


class MavlinkModule(Module):
    NAME = "mavlink"
    DESCRIPTION = "A MAVLink link for ground stations and SDKs (PX4's mavlink module): the stack as a PX4 autopilot"
    TRIGGER = Timer(1.0)
    DT_RANGE = (0.1, 10.0)
    OUTSIDE_LOCKSTEP = True
    PARAMS = catalogue.params("MAV_SYS_ID", "MAV_COMP_ID", "MAV_TYPE")
    PUBLISHES = (
        ORB_ID.vehicle_command,
        ORB_ID.telemetry_status,
        ORB_ID.mission,
        ORB_ID.manual_control_setpoint,
        ORB_ID.offboard_control_mode,
        *offboard.SETPOINT_TOPICS.values(),
    )
    """The vehicle's MAVLink identity: what it sends as, and which commands and messages are for it; MAV_TYPE
    is the HEARTBEAT's type, read at every heartbeat (PX4's mavlink module reads the parameter too)."""
    ARGS = (
        Arg(
            "device",
            "udp:127.0.0.1:18570",
            "The link: udp:HOST:PORT (bound there, answers whoever writes to it), serial:DEVICE:BAUD (a telemetry "
            "radio), tcpin:HOST:PORT, udpout:HOST:PORT",
        ),
        Arg("remote", "127.0.0.1:14550", "UDP: where to send until a peer has written (PX4's -o); empty: nowhere"),
        Arg(
            "shared_remote",
            False,
            "A ground station's link: in a swarm every vehicle's sends to this one remote, where the ground station "
            "tells them apart by system id (PX4's GCS links, all to 14550); otherwise vehicle i's link binds and "
            "sends i - 1 ports further (PX4's API links, 14580+i-1 to 14540+i-1)",
        ),
        Arg(
            "signing_key",
            "",
            "A file with a MAVLink 2 signing key (64 hex digits): sign everything, refuse unsigned messages "
            "except HEARTBEAT; empty: no signing",
        ),
    )

    def __init__(self, rt: Runtime) -> None:
        super().__init__(rt)
        a = self.args
        self.endpoint = parse_endpoint(str(a["device"]))
        remote = _remote(str(a["remote"]))
        key = signing.load_key(str(a["signing_key"])) if a["signing_key"] else None
        self.own = (int(self.params["MAV_SYS_ID"]), int(self.params["MAV_COMP_ID"]))
        self.clock = StampClock(rt.spec.lockstep, wall_clock_us)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.view = telemetry.VehicleView()
        self.presence = Presence(self.own)
        self.streams = StreamScheduler()
        self.parameters = params.ParamProtocol(self.own)
        self.transfer = MissionTransfer(self.own)
        self.progress = MissionProgress()
        self.pending = commands.PendingCommands(ACK_TIMEOUT_US)
        self.relay = offboard.OffboardRelay()
        self.manual = ManualInput()
        self.texts = StatustextSender()
        self.counts: dict[str, int] = dict.fromkeys(
            (
                "commands",
                "command_duplicates",
                "command_timeouts",
                "unsupported",
                "refused",
                "ignored",
                "handler_errors",
                "unstamped",
                "statustexts",
            ),
            0,
        )
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._wake_r, self._wake_w = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        self._param_source = BusParamSource(rt.node.session, rt.node.vehicle)
        self._param_worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="params")
        self._param_results: queue.SimpleQueue[tuple[params.ListJob | params.SetJob, Any]] = queue.SimpleQueue()
        self._param_pacer = ParamPacer(param_rate(self.endpoint.kind, self.endpoint.baud), wall_clock_us())
        self._mission_msg: MissionMsg | None = None
        self._download_key: tuple[int | None, bool, int | None] | None = None
        self._verdict_id: int | None = None
        self._active = False
        self._link_error: str | None = None
        self._builders = self._message_builders()
        self.link = MavlinkLink(
            self.endpoint,
            system_id=self.own[0],
            component_id=self.own[1],
            heartbeat=self._heartbeat,
            opener=_open(remote),
        )
        if key is not None:
            signing.enable(self.link.mav, key)
        self._subs = {
            topic: _Subscription(
                rt.node,
                topic,
                QUEUED_TOPICS.get(topic, 4),
                self._wake if topic == ORB_ID.vehicle_command_ack else None,
            )
            for topic in BASE_TOPICS
        }
        self._telemetry: list[_Subscription] = []
        self.log.info(
            "link %s%s, system %d, MAV_TYPE %d%s",
            self.endpoint,
            f" (sending to {remote[0]}:{remote[1]} until a peer writes)" if remote else "",
            self.own[0],
            int(self.params["MAV_TYPE"]),
            ", signed" if key is not None else "",
        )
        self._commander_host = self._watch_commander_host(rt.spec)
        self._thread = threading.Thread(target=self._link_loop, name="mavlink", daemon=True)
        self._thread.start()

    def _watch_commander_host(self, spec: ModuleSpec) -> HostWatch | None:
        """On a vehicle over several hosts, the commander's host when it is another: its loss is told by the link
        (the commander, who tells of the other hosts' losses, went with it; stack.bus.host_beats)."""
        host = next((h for h, names in spec.placement.items() if CommanderModule.NAME in names), spec.host)
        if host == spec.host or spec.lockstep:
            return None
        watch = HostWatch({host: spec.placement[host]}, spec.host, spec.host_lease_ms)
        self.watch_hosts(lambda beating, payload: watch.beat(beating, wall_clock_us(), payload))
        return watch

    def _heartbeat(self) -> dict[str, int]:
        """The HEARTBEAT's fields now: the commander's state, and MAV_TYPE as the parameter is now."""
        return identity.heartbeat(self.view.status, int(self.params["MAV_TYPE"]))

    # -- the link thread ------------------------------------------------------------------------------

    def _wake(self) -> None:
        with contextlib.suppress(OSError):  # full (a wake is pending) or, at shutdown, closed
            os.write(self._wake_w, b"\0")

    def _link_loop(self) -> None:
        while not self._stop.is_set():
            fd = self.link.fileno()
            wait = ACTIVE_WAIT_S if self._active or self.parameters.sending() else IDLE_WAIT_S
            select.select([self._wake_r] if fd is None else [self._wake_r, fd], [], [], wait)
            with contextlib.suppress(BlockingIOError):
                os.read(self._wake_r, 4096)
            try:
                with self._lock:
                    self._service()
            except Exception:
                self.rt.errors += 1
                self.log.exception("link thread: a step failed; carrying on")

    def _service(self) -> None:
        now = wall_clock_us()
        self._read_bus()
        for msg in self.link.poll(0.0):
            self._on_link_message(msg, now)
        self._note_link_error()
        self._periodic(now)

    def _note_link_error(self) -> None:
        error = self.link.error
        if error != self._link_error:
            self._link_error = error
            if error:
                self.log.warning("%s (retrying every 0.5 s)", error)
            else:
                self.log.info("link %s open", self.endpoint)

    def _send(self, msg: mavlink2.MAVLink_message) -> None:
        self.link.send(msg)

    def _say(self, severity: int, text: str) -> None:
        self.counts["statustexts"] += 1
        for msg in self.texts.messages(severity, text):
            self._send(msg)

    def _publish(self, topic: Topic, msg: Any) -> None:
        """Publish stamped with the stack's time; in lockstep nothing goes out before any time was seen."""
        stamp = self.clock.now()
        if stamp <= 0:
            self.counts["unstamped"] += 1
            return
        msg.timestamp = stamp
        self.publish(topic, msg)

    # -- the bus --------------------------------------------------------------------------------------

    def _read_bus(self) -> None:
        for sub in (*self._subs.values(), *self._telemetry):
            while (item := sub.sub.poll()) is not None:
                msg = item.msg
                self.clock.observe(msg.timestamp)
                field = VIEW_FIELDS.get(sub.topic)
                if field is not None:
                    setattr(self.view, field, msg)
                    if field == "status":
                        self._on_progress(self.progress.result)
                else:
                    self._bus_handlers[sub.topic](self, msg)

    def _on_ack(self, ack: VehicleCommandAck) -> None:
        answer = self.pending.answer(ack)
        if answer is not None:
            self._send(answer)

    def _on_log(self, log: Any) -> None:
        self._say(log.severity, log.text)  # also to a silent peer: what happened while it was away

    def _on_parameter_update(self, msg: Any) -> None:
        if self._active and self.parameters.loaded:
            self.parameters.refresh()
        else:
            self.parameters.loaded = False  # listed afresh when a peer next asks

    def _on_mission(self, msg: MissionMsg) -> None:
        self._mission_msg = msg
        self._refresh_download()

    def _on_mission_result(self, result: MissionResult) -> None:
        if self._verdict_id is not None and result.mission_id == self._verdict_id and self.transfer.judging:
            self._verdict_id = None
            self.transfer.verdict(result.valid)
            if not result.valid:
                self._say(M.MAV_SEVERITY_CRITICAL, f"Mission rejected: {result.reason}")
        self._on_progress(result)
        self._refresh_download()

    def _on_progress(self, result: MissionResult | None) -> None:
        nav_state = self.view.status.nav_state if self.view.status is not None else -1
        for msg in self.progress.update(result, nav_state):
            if self._active:
                self._send(msg)

    def _refresh_download(self) -> None:
        """The mission a download gets: the last ``mission`` message, once the navigator has accepted it."""
        result, msg = self.progress.result, self._mission_msg
        key = (
            result.mission_id if result is not None else None,
            result is not None and result.valid,
            msg.mission_id if msg is not None else None,
        )
        if key == self._download_key:
            return
        self._download_key = key
        self.transfer.items = mission_items.download_items(msg, result)

    _bus_handlers: ClassVar[dict[str, Callable[[MavlinkModule, Any], None]]] = {
        ORB_ID.vehicle_command_ack: _on_ack,
        ORB_ID.mavlink_log: _on_log,
        ORB_ID.parameter_update: _on_parameter_update,
        ORB_ID.mission: _on_mission,
        ORB_ID.mission_result: _on_mission_result,
    }

    # -- the link -------------------------------------------------------------------------------------

    def _on_link_message(self, msg: mavlink2.MAVLink_message, now: int) -> None:
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if source == self.own:
            return
        kind = msg.get_type()
        self.presence.on_message(source, now, msg.type if kind == "HEARTBEAT" else None)
        self._activate(now)
        handler = self._link_handlers.get(kind)
        if handler is None:
            if kind not in ("HEARTBEAT", "TIMESYNC"):
                self.counts["ignored"] += 1
            return
        try:
            handler(self, msg, source, now)
        except Exception:
            self.counts["handler_errors"] += 1
            self.rt.errors += 1
            if self.counts["handler_errors"] % ERROR_LOG_EVERY == 1:
                self.log.exception("%s from %d/%d: handling failed (dropped)", kind, *source)

    def _on_command(self, msg: Any, source: tuple[int, int], now: int) -> None:
        if not commands.addressed_to(msg.target_system, msg.target_component, self.own):
            return
        local = local_commands.answer(msg.command, msg.param1, msg.param2, self.streams, self._builders)
        if local is not None:
            result, param, replies = local
            self._send(commands.command_ack(msg.command, result, source, param))
            for reply in replies:  # after the acknowledgement, as the MAVLink command protocol has it
                self._send(reply)
            return
        cmd = commands.from_command(msg, source, self.own, SUPPORTED_COMMANDS, self.view.home)
        if isinstance(cmd, commands.Refusal):
            self.counts["unsupported" if cmd.result == M.MAV_RESULT_UNSUPPORTED else "refused"] += 1
            self._send(commands.command_ack(msg.command, cmd.result, source, cmd.param))
            if cmd.reason:
                self._say(M.MAV_SEVERITY_CRITICAL, cmd.reason)
            return
        self._forward(cmd, now)

    def _forward(self, cmd: VehicleCommand, now: int) -> None:
        if not self.pending.add(cmd, now):
            self.counts["command_duplicates"] += 1
            return
        self.counts["commands"] += 1
        self._publish(ORB_ID.vehicle_command, cmd)

    def _on_set_mode(self, msg: Any, source: tuple[int, int], now: int) -> None:
        if msg.target_system == self.own[0]:
            self.counts["commands"] += 1
            self._publish(ORB_ID.vehicle_command, commands.from_set_mode(msg, source, self.own))

    def _on_param_request_list(self, msg: Any, source: tuple[int, int], now: int) -> None:
        self.parameters.on_request_list(msg)

    def _on_param_request_read(self, msg: Any, source: tuple[int, int], now: int) -> None:
        self.parameters.on_request_read(msg)

    def _on_param_set(self, msg: Any, source: tuple[int, int], now: int) -> None:
        reason = self.parameters.on_set(msg)
        if reason:
            self.counts["refused"] += 1
            self._say(M.MAV_SEVERITY_ERROR, reason)

    def _on_mission_message(self, msg: Any, source: tuple[int, int], now: int) -> None:
        self.transfer.on_message(msg, source, now)

    def _on_manual_control(self, msg: Any, source: tuple[int, int], now: int) -> None:
        if msg.target != self.own[0]:
            return
        try:
            sticks = manual_control(msg, self.clock.now())
        except ValueError as e:
            self._refuse(str(e))
            return
        self.manual.on_sticks(sticks, now)
        self._publish(ORB_ID.manual_control_setpoint, sticks)

    def _on_setpoint(self, msg: Any, source: tuple[int, int], now: int) -> None:
        if msg.target_system != self.own[0]:
            return
        stamp = self.clock.now()
        try:
            if msg.get_type() == "SET_ATTITUDE_TARGET":
                setpoint, mode = offboard.attitude_target(msg, stamp)
            else:
                lpos = self.view.local_position
                heading = lpos.heading if lpos is not None else math.nan
                setpoint, mode = offboard.position_target(msg, heading, stamp)
        except offboard.Refused as e:
            self._refuse(f"{msg.get_type()} refused: {e}")
            return
        self.relay.on_setpoint(setpoint, mode, now)

    def _on_ping(self, msg: Any, source: tuple[int, int], now: int) -> None:
        if msg.target_system == 0 and msg.target_component == 0:  # a request; an answer names its receiver
            self._send(M.MAVLink_ping_message(msg.time_usec, msg.seq, *source))

    def _refuse(self, why: str) -> None:
        self.counts["refused"] += 1
        self.rt.rejected += 1
        if self.counts["refused"] % ERROR_LOG_EVERY == 1:
            self.log.warning("%s (%d refused so far)", why, self.counts["refused"])

    _link_handlers: ClassVar[dict[str, Callable[[MavlinkModule, Any, tuple[int, int], int], None]]] = {
        "COMMAND_LONG": _on_command,
        "COMMAND_INT": _on_command,
        "SET_MODE": _on_set_mode,
        "PARAM_REQUEST_LIST": _on_param_request_list,
        "PARAM_REQUEST_READ": _on_param_request_read,
        "PARAM_SET": _on_param_set,
        **dict.fromkeys(MissionTransfer._handlers, _on_mission_message),
        "MANUAL_CONTROL": _on_manual_control,
        "SET_POSITION_TARGET_LOCAL_NED": _on_setpoint,
        "SET_ATTITUDE_TARGET": _on_setpoint,
        "PING": _on_ping,
    }

    # -- what is due ----------------------------------------------------------------------------------

    def _activate(self, now: int) -> None:
        """Read the telemetry topics while a peer uses the link, and only then."""
        active = self.presence.active(now)
        if active == self._active:
            return
        self._active = active
        if active:
            self.log.info("a peer uses the link: streaming")
            self.streams.restart(now)
            self._telemetry = [_Subscription(self.rt.node, topic, 4) for topic in TELEMETRY_TOPICS]
            if not self.parameters.loaded:
                self.parameters.refresh()
        else:
            self.log.info("no peer on the link for a while: streams stopped")
            for sub in self._telemetry:
                sub.close()
            self._telemetry = []
            self.view.clear_telemetry()

    def _periodic(self, now: int) -> None:
        self._activate(now)
        if self._commander_host is not None:
            for change in self._commander_host.update(now):
                self.log.warning("%s", change.describe())
                severity = mavlink2.MAV_SEVERITY_CRITICAL if change.lost else mavlink2.MAV_SEVERITY_INFO
                self._say(severity, change.describe())
        flags = self.presence.telemetry_due(now)
        if flags is not None:
            self._publish(ORB_ID.telemetry_status, telemetry_status(self.endpoint.kind, flags))
        if self._active:
            for msg_id in self.streams.due(now):
                message = self._builders[msg_id]()
                if message is not None:
                    self._send(message)
        self._missions(now)
        for ack in self.pending.expired(now):
            self.counts["command_timeouts"] += 1
            self._send(ack)
        self._parameters(now)
        stamp = self.clock.now()
        if stamp > 0:
            in_offboard = self.view.status is not None and self.view.status.nav_state == NS.NAVIGATION_STATE_OFFBOARD
            for topic, msg in self.relay.due(now, stamp, in_offboard):
                self.publish(topic, msg)
            sticks = self.manual.due(now, stamp)
            if sticks is not None:
                self.publish(ORB_ID.manual_control_setpoint, sticks)

    def _missions(self, now: int) -> None:
        self.transfer.tick(now)
        out, actions = self.transfer.take()
        for msg in out:
            self._send(msg)
        for action in actions:
            if isinstance(action, Upload):
                self._upload(action.items)
            elif isinstance(action, Clear):
                self._verdict_id = None
                self._publish(ORB_ID.mission, mission_message(Mission(()), None, mission_id_for(Mission(()))))
            elif isinstance(action, Refused):
                self._say(M.MAV_SEVERITY_CRITICAL, f"Mission rejected: {action.reason}")
            elif isinstance(action, SetCurrent):
                cmd = VehicleCommand(
                    command=VehicleCommand.VEHICLE_CMD_DO_SET_MISSION_CURRENT,
                    param1=float(action.seq),
                    target_system=self.own[0],
                    target_component=self.own[1],
                    source_system=action.source[0],
                    source_component=action.source[1],
                )
                self._publish(ORB_ID.vehicle_command, cmd)
        out, _ = self.transfer.take()  # a verdict given while converting
        for msg in out:
            self._send(msg)

    def _upload(self, items: list[Any]) -> None:
        home = mission_items.mission_home(self.view.home, self.view.local_position)
        try:
            mission = mission_items.mission_from_upload(items, home, f"mavlink:{self.rt.name}")
        except mission_items.ItemRefused as e:
            self.transfer.verdict(False, e.mission_result)
            self._say(M.MAV_SEVERITY_CRITICAL, f"Mission rejected: {e}")
            return
        self._verdict_id = mission_id_for(mission)
        self._publish(ORB_ID.mission, mission_message(mission, home, self._verdict_id))

    def _parameters(self, now: int) -> None:
        for job in self.parameters.take_jobs():
            future = self._param_worker.submit(self._run_param_job, job)
            future.add_done_callback(lambda f, job=job: self._param_done(job, f))
        while True:
            try:
                job, result = self._param_results.get_nowait()
            except queue.Empty:
                break
            if isinstance(job, params.ListJob):
                if isinstance(result, Exception):
                    self.log.warning("listing the parameters failed: %s", result)
                    self.parameters.on_list_failed()
                else:
                    self.parameters.on_list(result)
            else:
                reason = self.parameters.on_set_result(job.name, result)
                if reason:
                    self.counts["refused"] += 1
                    self._say(M.MAV_SEVERITY_ERROR, reason)
        count = self._param_pacer.allow(now, self.parameters.sending())
        if count:
            for msg in self.parameters.take(count):
                self._send(msg)

    def _run_param_job(self, job: params.ListJob | params.SetJob) -> Any:
        if isinstance(job, params.ListJob):
            return self._param_source.list()
        try:
            return self._param_source.set(job.name, job.value)
        except ParamError as e:
            return e

    def _param_done(self, job: params.ListJob | params.SetJob, future: Any) -> None:
        error = future.exception()
        self._param_results.put((job, error if error is not None else future.result()))
        self._wake()

    # -- messages on request and in streams -----------------------------------------------------------

    def _message_builders(self) -> dict[int, Callable[[], mavlink2.MAVLink_message | None]]:
        view, now = self.view, self.clock.now

        def sys_status() -> mavlink2.MAVLink_message:
            c = self.link.counters
            drop = 1.0 - c.quality if self.link.connected else 0.0
            return telemetry.sys_status(view, now(), drop, c.crc_errors + c.parse_errors)

        def of(build: Callable[[telemetry.VehicleView, int], mavlink2.MAVLink_message | None]) -> Callable[[], Any]:
            return lambda: build(view, now())

        return {
            M.MAVLINK_MSG_ID_AUTOPILOT_VERSION: lambda: identity.autopilot_version(self.rt.node.vehicle, self.own[0]),
            M.MAVLINK_MSG_ID_SYS_STATUS: sys_status,
            M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: of(telemetry.extended_sys_state),
            M.MAVLINK_MSG_ID_ATTITUDE: of(telemetry.attitude),
            M.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: of(telemetry.attitude_quaternion),
            M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: of(telemetry.global_position_int),
            M.MAVLINK_MSG_ID_LOCAL_POSITION_NED: of(telemetry.local_position_ned),
            M.MAVLINK_MSG_ID_GPS_RAW_INT: of(telemetry.gps_raw_int),
            M.MAVLINK_MSG_ID_HOME_POSITION: of(telemetry.home_position),
            M.MAVLINK_MSG_ID_BATTERY_STATUS: of(telemetry.battery_status),
            M.MAVLINK_MSG_ID_VFR_HUD: of(telemetry.vfr_hud),
            M.MAVLINK_MSG_ID_MISSION_CURRENT: self.progress.current,
        }

    # -- the runtime's side ---------------------------------------------------------------------------

    def run(self, msg: None, dt: float) -> None:
        if not self._thread.is_alive():
            raise RuntimeError("the link thread has stopped")

    def status(self) -> dict[str, float | int | str | bool]:
        with self._lock:
            c = self.link.counters
            now = wall_clock_us()
            figures: dict[str, float | int | str | bool] = {
                "bytes_in": c.bytes_in,
                "bytes_out": c.bytes_out,
                "packets_in": c.packets_in,
                "packets_out": c.packets_out,
                "send_drops": c.send_drops,
                "crc_errors": c.crc_errors,
                "parse_errors": c.parse_errors,
                "unknown_messages": c.unknown_messages,
                "open_failures": c.open_failures,
                "link_error": self.link.error or "",
                "bus_in": sum(s.sub.received for s in (*self._subs.values(), *self._telemetry)),
                "peers": self.presence.peer_count(now),
                "gcs": self.presence.gcs(now),
                "active": self._active,
                "pending_commands": len(self.pending),
                "params_served": len(self.parameters.entries),
                "params_skipped": self.parameters.skipped,
                "mission_uploads": self.transfer.uploads,
                "mission_downloads": self.transfer.downloads,
                "mission_refusals": self.transfer.refused,
                "signature_refusals": signing.refused(self.link.mav),
                **self.counts,
            }
        return figures

    def close(self) -> None:
        self._stop.set()
        self._wake()
        self._thread.join(timeout=2.0)
        self._param_worker.shutdown(wait=False, cancel_futures=True)
        with self._lock:
            self.link.close()
            for sub in (*self._subs.values(), *self._telemetry):
                sub.close()
        os.close(self._wake_r)
        os.close(self._wake_w)
