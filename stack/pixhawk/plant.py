"""What the ``pixhawk`` plant module decides, I/O-free: which streams to ask for, the COMMAND_LONG
transactions, and the hand-off of arming and Offboard between the stack's commander and the Pixhawk.

**Streams.** :func:`stream_plan` asks for HIGHRES_IMU at the attitude-loop rate (250 Hz) or the highest
rate the link carries: on a serial link the inbound streams keep within half of the UART's bytes per
second (10 bits a byte), the rest left to PX4's other streams and to bursts; when they do not fit, every
stream slows in proportion, the IMU no lower than 50 Hz (at 921600 baud all fit).

**Commands** (MAVLink command protocol, https://mavlink.io/en/services/command.html): a COMMAND_LONG is
resent with ``confirmation`` + 1 until its COMMAND_ACK arrives (IN_PROGRESS extends the wait), at most
``COMMAND_ATTEMPTS`` times; the ACK's result is the outcome, and a refusal's reason is the last warning
the Pixhawk sent as STATUSTEXT (PX4 says why it denies arming there, not in the ACK).

**Hand-off** (:class:`Handoff`). The stack's commander decides; the Pixhawk's HEARTBEAT is the truth:

* while the stack is disarmed and the Pixhawk too, the adapter streams an idle SET_ATTITUDE_TARGET as
  proof of life (PX4 accepts Offboard only with a setpoint stream, ``docs/en/flight_modes/offboard.md``);
* when the commander arms, the adapter switches the Pixhawk to OFFBOARD (MAV_CMD_DO_SET_MODE) and arms
  it (MAV_CMD_COMPONENT_ARM_DISARM). The commander holds its acknowledgement until the Pixhawk is armed
  (``external_autopilot_status.armed``), or refuses the command with the Pixhawk's reason
  (``refusals``/``refusal``) and disarms;
* when the Pixhawk leaves Offboard on its own while armed (its Offboard-loss failsafe, a pilot's switch)
  the adapter yields: it never forces Offboard back. It asks for Offboard again only when the stack's
  commander accepts a new command that sets a mode (the user takes over again);
* when the Pixhawk disarms on its own, the commander disarms (the truth wins); when the commander
  disarms, the adapter disarms the Pixhawk if it is armed in Offboard (else a pilot flies it, and it is
  left alone) and stops streaming, so a refused disarm in the air leaves the Pixhawk to its own
  Offboard-loss failsafe instead of cutting the thrust.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from enum import Enum

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.msg.system import command_label

# -- streams ---------------------------------------------------------------------------------------------

MAVLINK2_OVERHEAD = 12
"""Bytes a MAVLink 2 frame adds to its payload: 10 of header, 2 of checksum (unsigned)."""
UART_BITS_PER_BYTE = 10
INBOUND_SHARE = 0.5
IMU_RATE_HZ = 250.0
IMU_RATE_MIN_HZ = 50.0


def frame_bytes(msg_class: type[mavlink2.MAVLink_message]) -> int:
    """The longest MAVLink 2 frame of a message (its payload with extensions, untruncated)."""
    return msg_class.unpacker.size + MAVLINK2_OVERHEAD


@dataclass(frozen=True, slots=True)
class Stream:
    msg_class: type[mavlink2.MAVLink_message]
    hz: float
    """Requested rate; 0 asks the autopilot to stop the stream (interval −1)."""

    @property
    def msg_id(self) -> int:
        return self.msg_class.id

    @property
    def interval_us(self) -> int:
        return round(1e6 / self.hz) if self.hz > 0 else -1

    @property
    def bytes_per_s(self) -> float:
        return self.hz * frame_bytes(self.msg_class)


def stream_plan(baud: int | None, autopilot_estimate: bool, imu_rate_hz: float = IMU_RATE_HZ) -> list[Stream]:
    """The streams the adapter asks for (MAV_CMD_SET_MESSAGE_INTERVAL); ``baud`` None for a network link.

    The Pixhawk's estimate comes at the loop rates when the stack flies on it (ATTITUDE_QUATERNION with the
    IMU, LOCAL_POSITION_NED at the position loop's 50 Hz), else at 50 Hz for plots. ATTITUDE and ODOMETRY,
    which PX4 streams on an onboard link, are turned off: ATTITUDE_QUATERNION and LOCAL_POSITION_NED say the
    same in fewer bytes."""
    others = [
        Stream(mavlink2.MAVLink_gps_raw_int_message, 10.0),
        Stream(mavlink2.MAVLink_attitude_quaternion_message, imu_rate_hz if autopilot_estimate else 50.0),
        Stream(mavlink2.MAVLink_local_position_ned_message, 50.0),
        Stream(mavlink2.MAVLink_sim_state_message, 50.0),
        Stream(mavlink2.MAVLink_battery_status_message, 2.0),
        Stream(mavlink2.MAVLink_sys_status_message, 2.0),
        Stream(mavlink2.MAVLink_attitude_message, 0.0),
        Stream(mavlink2.MAVLink_odometry_message, 0.0),
    ]
    imu = Stream(mavlink2.MAVLink_highres_imu_message, imu_rate_hz)
    if baud is None:
        return [imu, *others]
    budget = INBOUND_SHARE * link_budget_bytes_per_s(baud)
    others_bytes = sum(s.bytes_per_s for s in others)
    scale = min(1.0, budget / (imu.bytes_per_s + others_bytes))
    if scale == 1.0:
        return [imu, *others]
    imu = Stream(imu.msg_class, max(IMU_RATE_MIN_HZ, imu.hz * scale))
    others_scale = max(0.0, budget - imu.bytes_per_s) / others_bytes
    return [imu, *(Stream(s.msg_class, s.hz * others_scale) for s in others)]


def link_budget_bytes_per_s(baud: int) -> float:
    """What a UART at ``baud`` carries each way (8N1: 10 bits a byte)."""
    return baud / UART_BITS_PER_BYTE


# -- commands --------------------------------------------------------------------------------------------

COMMAND_TIMEOUT_US = 200_000
COMMAND_ATTEMPTS = 6
STATUSTEXT_REASON_US = 1_000_000
"""A STATUSTEXT warning this recent gives the reason of a refusal."""

RESULT_NAMES = {
    mavlink2.MAV_RESULT_ACCEPTED: "accepted",
    mavlink2.MAV_RESULT_TEMPORARILY_REJECTED: "temporarily rejected",
    mavlink2.MAV_RESULT_DENIED: "denied",
    mavlink2.MAV_RESULT_UNSUPPORTED: "unsupported",
    mavlink2.MAV_RESULT_FAILED: "failed",
    mavlink2.MAV_RESULT_IN_PROGRESS: "in progress",
    6: "cancelled",  # MAV_RESULT_CANCELLED, newer than pymavlink 2.4.50's common dialect
}


@dataclass(frozen=True, slots=True)
class CommandLong:
    """A COMMAND_LONG to send (params 1–7; ``confirmation`` counts the resends)."""

    command: int
    params: tuple[float, float, float, float, float, float, float]
    confirmation: int = 0


def set_mode_command(mode: Px4Mode) -> CommandLong:
    """MAV_CMD_DO_SET_MODE with PX4's custom main/sub mode (px4_custom_mode.h) and CUSTOM_MODE_ENABLED."""
    base = float(mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
    return CommandLong(mavlink2.MAV_CMD_DO_SET_MODE, (base, mode.main_mode, mode.sub_mode, 0.0, 0.0, 0.0, 0.0))


def arm_command(arm: bool) -> CommandLong:
    return CommandLong(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, (1.0 if arm else 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))


def message_interval_command(stream: Stream) -> CommandLong:
    return CommandLong(
        mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, (float(stream.msg_id), float(stream.interval_us), 0, 0, 0, 0, 0)
    )


@dataclass(slots=True)
class Transaction:
    """One command in flight: sent at ``sent_us``, ``attempts`` times so far."""

    command: CommandLong
    sent_us: int = 0
    attempts: int = 0
    result: int | None = None
    reason: str = ""


class Commands:
    """COMMAND_LONG transactions, one per command id at a time (a newer one replaces an older)."""

    def __init__(self, timeout_us: int = COMMAND_TIMEOUT_US, attempts: int = COMMAND_ATTEMPTS) -> None:
        self.timeout_us = timeout_us
        self.attempts = attempts
        self.active: dict[int, Transaction] = {}
        self.finished: list[Transaction] = []
        self._warnings: deque[tuple[int, str]] = deque(maxlen=4)

    def start(self, command: CommandLong) -> None:
        self.active[command.command] = Transaction(command)

    def busy(self, command_id: int) -> bool:
        return command_id in self.active

    def on_statustext(self, now_us: int, severity: int, text: str) -> None:
        if severity <= mavlink2.MAV_SEVERITY_WARNING:
            self._warnings.append((now_us, text))

    def on_ack(self, now_us: int, command_id: int, result: int) -> Transaction | None:
        """An ACK: the transaction it finishes (None for an ACK of nothing outstanding, or IN_PROGRESS)."""
        t = self.active.get(command_id)
        if t is None:
            return None
        if result == mavlink2.MAV_RESULT_IN_PROGRESS:
            t.sent_us = now_us  # the autopilot works on it: wait another timeout before resending
            return None
        del self.active[command_id]
        t.result = result
        if result != mavlink2.MAV_RESULT_ACCEPTED:
            t.reason = RESULT_NAMES.get(result, f"result {result}")
            recent = [text for stamp, text in self._warnings if now_us - stamp <= STATUSTEXT_REASON_US]
            if recent:
                t.reason += f": {recent[-1]}"
        self.finished.append(t)
        return t

    def due(self, now_us: int) -> list[CommandLong]:
        """Commands to send now: new ones and resends; a transaction out of attempts fails ("no answer")."""
        out = []
        for command_id, t in list(self.active.items()):
            if t.attempts and now_us - t.sent_us < self.timeout_us:
                continue
            if t.attempts >= self.attempts:
                del self.active[command_id]
                t.reason = f"no answer after {t.attempts} attempts"
                self.finished.append(t)
                continue
            t.sent_us = now_us
            out.append(CommandLong(t.command.command, t.command.params, confirmation=t.attempts))
            t.attempts += 1
        return out


# -- the hand-off ----------------------------------------------------------------------------------------


class Control(Enum):
    """Who flies: nobody (disarmed), the stack being handed control, the stack, the Pixhawk on its own."""

    IDLE = "idle"
    TAKING_CONTROL = "taking control"
    IN_CONTROL = "in control"
    YIELDED = "yielded"


@dataclass(slots=True)
class AutopilotView:
    """What the Pixhawk's HEARTBEAT and SYS_STATUS say (armed and mode also move on an accepted command,
    until the next heartbeat)."""

    connected: bool = False
    armed: bool = False
    custom_mode: int = 0
    system_status: int = 0
    prearm_ok: bool | None = None
    heartbeat_us: int = 0
    connected_us: int = 0
    """When the link (last) came up."""

    @property
    def mode(self) -> Px4Mode | None:
        return px4_modes.decode(self.custom_mode)

    @property
    def offboard(self) -> bool:
        return self.mode is Px4Mode.OFFBOARD

    @property
    def armable(self) -> bool:
        if self.prearm_ok is not None:
            return self.prearm_ok
        return self.system_status == mavlink2.MAV_STATE_STANDBY


@dataclass(slots=True)
class Handoff:
    """The arming and Offboard hand-off (module docstring). Feed it the Pixhawk's messages and the stack's
    arming state; ``tick`` returns the commands to send; ``events`` collects what the log should say."""

    commands: Commands = field(default_factory=Commands)
    view: AutopilotView = field(default_factory=AutopilotView)
    control: Control = Control.IDLE
    stack_armed: bool = False
    refusals: int = 0
    refusal: str = ""
    events: list[str] = field(default_factory=list)
    _refused: bool = False
    _resume: bool = False

    # -- inputs ---------------------------------------------------------------------------------------

    def on_heartbeat(self, now_us: int, base_mode: int, custom_mode: int, system_status: int) -> None:
        v = self.view
        armed = bool(base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)
        if custom_mode != v.custom_mode and v.heartbeat_us:
            self.events.append(f"Pixhawk mode {px4_modes.describe(v.custom_mode)} → {px4_modes.describe(custom_mode)}")
        if armed != v.armed and v.heartbeat_us:
            self.events.append(f"Pixhawk {'armed' if armed else 'disarmed'} ({px4_modes.describe(custom_mode)})")
        v.armed, v.custom_mode, v.system_status, v.heartbeat_us = armed, custom_mode, system_status, now_us

    def on_connection(self, now_us: int, connected: bool) -> None:
        if connected != self.view.connected:
            self.events.append("Pixhawk link " + ("up" if connected else "lost"))
            if connected:
                self.view.connected_us = now_us
        self.view.connected = connected

    def on_sys_status(self, prearm_ok: bool | None) -> None:
        self.view.prearm_ok = prearm_ok

    def on_statustext(self, now_us: int, severity: int, text: str) -> None:
        self.commands.on_statustext(now_us, severity, text)

    def on_ack(self, now_us: int, command_id: int, result: int) -> None:
        t = self.commands.on_ack(now_us, command_id, result)
        if t is None or result != mavlink2.MAV_RESULT_ACCEPTED:
            return
        if command_id == mavlink2.MAV_CMD_DO_SET_MODE:
            self.view.custom_mode = px4_modes.encode(Px4Mode.OFFBOARD)
        elif command_id == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM:
            self.view.armed = t.command.params[0] == 1.0

    def on_stack_armed(self, armed: bool) -> None:
        if armed and not self.stack_armed:
            self._refused = False
        self.stack_armed = armed

    def on_stack_mode_command(self) -> None:
        """The commander accepted a command that sets a mode: after a yield, ask for Offboard again."""
        if self.control is Control.YIELDED:
            self._resume = True
            self._refused = False

    # -- decisions --------------------------------------------------------------------------------------

    def tick(self, now_us: int) -> list[CommandLong]:
        self._collect_outcomes()
        v = self.view
        if not v.connected:
            if self.control is Control.IN_CONTROL:
                self._set_control(Control.YIELDED, "link lost: the Pixhawk flies on its own")
            return []  # commands in flight wait: a short gap costs them nothing, a long one their attempts
        if v.heartbeat_us < v.connected_us:
            return []  # back from a gap: what the Pixhawk did meanwhile, its next heartbeat says
        if self.stack_armed:
            self._when_stack_armed()
        else:
            self._when_stack_disarmed()
        return self.commands.due(now_us)

    def _when_stack_armed(self) -> None:
        v = self.view
        if v.armed and v.offboard:
            if self.control is not Control.IN_CONTROL:
                self._set_control(Control.IN_CONTROL, "the Pixhawk flies the stack's setpoints (OFFBOARD)")
            self._resume = False
            return
        if self.control is Control.IN_CONTROL:
            self._set_control(Control.YIELDED, f"the Pixhawk left Offboard on its own: {self._mode_name()}")
            return
        if self.control is Control.YIELDED and not self._resume:
            return
        if self._refused:
            return
        if self.control is Control.IDLE:
            self._set_control(Control.TAKING_CONTROL, "switching the Pixhawk to Offboard and arming it")
        if not v.offboard:
            self._ensure(set_mode_command(Px4Mode.OFFBOARD))
        elif not v.armed:
            self._ensure(arm_command(True))

    def _when_stack_disarmed(self) -> None:
        v = self.view
        self._resume = False
        if self.control is not Control.IDLE:
            self._set_control(Control.IDLE, "the stack disarmed")
        self.commands.active.pop(mavlink2.MAV_CMD_DO_SET_MODE, None)
        arming = self.commands.active.get(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM)
        if arming is not None and arming.command.params[0] == 1.0:
            del self.commands.active[mavlink2.MAV_CMD_COMPONENT_ARM_DISARM]
        if v.armed and v.offboard:  # armed in Offboard: the stack's to disarm (a pilot's mode is left alone)
            self._ensure(arm_command(False))

    def _ensure(self, command: CommandLong) -> None:
        active = self.commands.active.get(command.command)
        if active is None or active.command.params != command.params:
            self.commands.start(command)

    def _collect_outcomes(self) -> None:
        for t in self.commands.finished:
            if t.result == mavlink2.MAV_RESULT_ACCEPTED:
                continue
            what = _describe(t.command)
            self.events.append(f"Pixhawk refused {what}: {t.reason}")
            if t.command.command == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM and t.command.params[0] == 0.0:
                continue  # a refused disarm is reported, and the Pixhawk's own failsafe takes over
            self.refusals += 1
            self.refusal = f"the Pixhawk refused {what}: {t.reason}"
            self._refused = True
            self._resume = False
        self.commands.finished.clear()

    def _set_control(self, control: Control, why: str) -> None:
        self.control = control
        self.events.append(f"control: {control.value} ({why})")

    def _mode_name(self) -> str:
        return px4_modes.describe(self.view.custom_mode)

    # -- outputs ------------------------------------------------------------------------------------------

    @property
    def in_control(self) -> bool:
        return self.control is Control.IN_CONTROL

    @property
    def stream(self) -> bool:
        """Stream the stack's setpoints (armed): while taking or holding control, and after a yield (PX4
        needs the stream to accept Offboard again)."""
        return self.stack_armed and self.view.connected

    @property
    def proof_of_life(self) -> bool:
        """Stream the idle setpoint: the stack and the Pixhawk are both disarmed."""
        return not self.stack_armed and not self.view.armed and self.view.connected


def _describe(command: CommandLong) -> str:
    if command.command == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM:
        return "to arm" if command.params[0] == 1.0 else "to disarm"
    if command.command == mavlink2.MAV_CMD_DO_SET_MODE:
        main, sub = round(command.params[1]), round(command.params[2])
        return f"mode {px4_modes.describe((main << 16) | (sub << 24))}"
    return f"command {command_label(command.command)}"


# -- latency ---------------------------------------------------------------------------------------------


class LatencyStats:
    """Percentiles of the age of each setpoint sent (µs from its gyro sample), over the last samples."""

    def __init__(self, window: int = 2000) -> None:
        self.samples: deque[int] = deque(maxlen=window)

    def add(self, age_us: int) -> None:
        self.samples.append(age_us)

    def percentile(self, p: float) -> float:
        if not self.samples:
            return math.nan
        ordered = sorted(self.samples)
        return float(ordered[min(len(ordered) - 1, int(p / 100.0 * len(ordered)))])
