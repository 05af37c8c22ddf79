"""What the ``pixhawk`` module makes of its link to the Pixhawk, I/O-free: whether the Pixhawk is heard, which of
its streams to ask for again, a sample's time on the stack's clock, which COMMAND_ACKs are for the adapter, and the
``external_autopilot_status`` it publishes.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.mavlink.link import LinkCounters
from stack.mavlink.timesync import TimeSync
from stack.msg.system import ExternalAutopilotStatus
from stack.pixhawk import convert, plant

SILENCE_US = 500_000
"""The link also counts as lost after this long without any message (the IMU streams at up to 250 Hz), so
a cut shows in half a second (before the stack's estimates time out, in 1 s), while a lost heartbeat or two
(1 Hz) does not drop the link."""
STREAM_CHECK_US = 1_000_000
STREAM_REQUESTS = 5
"""How often a stream the Pixhawk does not deliver at half the asked rate is asked for again."""
MAV_COMP_ID_ONBOARD_COMPUTER = 191


def sample_us(timesync: TimeSync, remote_us: int, now_us: int) -> int:
    """The autopilot's sample time on the stack's clock (the receive time until the clocks are synced, or for a
    Unix time, which TIMESYNC does not map); never later than its arrival."""
    if not timesync.synced or convert.is_unix_time(remote_us):
        return now_us
    return min(timesync.to_local_us(remote_us), now_us)


class Liveness:
    """Whether the Pixhawk is heard: ``on_receive(now)`` for each poll that brought messages."""

    def __init__(self) -> None:
        self.last_rx_us = 0
        self.data_resumed_us = 0

    def on_receive(self, now_us: int) -> None:
        if now_us - self.last_rx_us >= SILENCE_US:
            self.data_resumed_us = now_us
        self.last_rx_us = now_us

    def connected(self, now_us: int, heard: bool, heartbeat_fresh: bool, link_timeout_us: int) -> bool:
        """Data within SILENCE_US from a Pixhawk ``heard`` (its HEARTBEAT seen), and its heartbeat within the link
        timeout (``heartbeat_fresh``) or, counted from when data came back after a gap, not yet due (the next
        1 Hz heartbeat may be a second away)."""
        if not heard or now_us - self.last_rx_us >= SILENCE_US:
            return False
        return heartbeat_fresh or now_us - self.data_resumed_us < link_timeout_us


class StreamWatch:
    """Counts what arrives and (re)asks, every STREAM_CHECK_US, for each stream of the plan not arriving at half
    its rate (or arriving when it should be off, or never asked yet), at most STREAM_REQUESTS times per
    connection."""

    def __init__(self, plan: list[plant.Stream]) -> None:
        self.plan = plan
        self.counts: dict[int, int] = {}
        self.requests: dict[int, int] = {}
        self._check_us = 0

    def on_message(self, msg_id: int) -> None:
        self.counts[msg_id] = self.counts.get(msg_id, 0) + 1

    def check(self, now_us: int, connected: bool) -> list[plant.CommandLong]:
        """The MAV_CMD_SET_MESSAGE_INTERVAL commands to send now."""
        if not connected:
            self.requests.clear()
            return []
        if now_us - self._check_us < STREAM_CHECK_US:
            return []
        span_s = (now_us - self._check_us) * 1e-6 if self._check_us else 0.0
        self._check_us = now_us
        out = []
        for stream in self.plan:
            received = self.counts.get(stream.msg_id, 0)
            slow = stream.hz > 0 and (span_s == 0.0 or received < 0.5 * stream.hz * span_s)
            stopped = stream.hz == 0 and received > 0
            asked = self.requests.get(stream.msg_id, 0)
            if (slow or stopped or asked == 0) and asked < STREAM_REQUESTS:
                self.requests[stream.msg_id] = asked + 1
                out.append(plant.message_interval_command(stream))
        self.counts.clear()
        return out


def ack_for_adapter(target_system: int, target_component: int, system_id: int) -> bool:
    """A COMMAND_ACK for the adapter: to its system (or broadcast) and its component (or broadcast)."""
    return target_system in (0, system_id) and target_component in (0, MAV_COMP_ID_ONBOARD_COMPUTER)


def external_status(
    now_us: int, handoff: plant.Handoff, autopilot: tuple[int, int] | None, counters: LinkCounters
) -> ExternalAutopilotStatus:
    """``external_autopilot_status``: the Pixhawk as its HEARTBEAT says, who flies, the link's health."""
    v = handoff.view
    peer = autopilot or (0, 0)
    return ExternalAutopilotStatus(
        timestamp=now_us,
        connected=v.connected,
        system_id=peer[0],
        component_id=peer[1],
        autopilot=mavlink2.MAV_AUTOPILOT_PX4 if autopilot else 0,
        armed=v.armed,
        custom_mode=v.custom_mode,
        mode=px4_modes.describe(v.custom_mode) if v.heartbeat_us else "",
        system_status=v.system_status,
        armable=v.armable,
        offboard=v.offboard,
        in_control=handoff.in_control,
        refusals=handoff.refusals,
        refusal=handoff.refusal,
        link_losses=counters.link_losses,
        link_quality=counters.quality,
    )
