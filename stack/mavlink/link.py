"""A MAVLink 2 link to one peer: framing, heartbeats, link loss and reopening, TIMESYNC, counters.

The encoder is pymavlink's MAVLink 2 common dialect imported directly, so the wire version never depends on the
MAVLINK20 / MAVLINK_DIALECT environment variables that ``mavutil`` reads.
"""

from __future__ import annotations

import math
import select
import time
from collections.abc import Callable

import msgspec
from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink.endpoint import Endpoint, parse_endpoint
from stack.mavlink.framing import FrameParser
from stack.mavlink.timesync import TimeSync
from stack.mavlink.transport import Transport, open_transport

HEARTBEAT_PERIOD_US = 1_000_000
TIMESYNC_PERIOD_US = 100_000  # PX4 streams TIMESYNC at 10 Hz on an onboard link
REOPEN_PERIOD_US = 500_000
QUALITY_WINDOW_S = 5.0


def monotonic_us() -> int:
    """CLOCK_MONOTONIC in µs, the stack's clock in real-time runs."""
    return time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000


def companion_heartbeat() -> dict:
    return {
        "type": mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
        "autopilot": mavlink2.MAV_AUTOPILOT_INVALID,
        "base_mode": 0,
        "custom_mode": 0,
        "system_status": mavlink2.MAV_STATE_ACTIVE,
    }


class LinkCounters(msgspec.Struct):
    bytes_in: int = 0
    bytes_out: int = 0
    packets_in: int = 0
    packets_out: int = 0
    send_drops: int = 0  # messages that could not be sent (link down, no peer address yet, stream backlog full)
    crc_errors: int = 0
    parse_errors: int = 0  # gaps of bytes that are not MAVLink, truncated frames
    unknown_messages: int = 0
    seq_gaps: int = 0  # packets lost, by sequence number
    link_losses: int = 0
    reconnects: int = 0
    open_failures: int = 0  # attempts to open the endpoint that failed (device missing, port in use...)
    quality: float = 0.0  # received / (received + lost) over the last few seconds; 0 while disconnected


class _LinkWriter:
    """The ``file`` pymavlink's encoder writes packed frames to."""

    def __init__(self, link: MavlinkLink) -> None:
        self.link = link

    def write(self, frame: bytes) -> None:
        self.link._write(frame)


class MavlinkLink:
    """One endpoint, one peer. Call ``poll()`` often (it also sends what is due); ``fileno()`` may change when the
    transport is reopened. A udpin endpoint answers whoever sent last, and cannot send before someone has.
    ``opener`` opens the endpoint's transport (and is retried every REOPEN_PERIOD_US while it raises OSError)."""

    def __init__(
        self,
        endpoint: str | Endpoint,
        *,
        system_id: int,
        component_id: int,
        heartbeat: Callable[[], dict] | None = None,
        link_timeout_s: float = 1.5,
        timesync: bool = False,
        clock_us: Callable[[], int] = monotonic_us,
        opener: Callable[[Endpoint], Transport] = open_transport,
    ) -> None:
        self.endpoint = endpoint if isinstance(endpoint, Endpoint) else parse_endpoint(endpoint)
        self.system_id = system_id
        self.component_id = component_id
        self.heartbeat = heartbeat or companion_heartbeat
        self.link_timeout_us = int(link_timeout_s * 1e6)
        self.send_timesync = timesync
        self.clock_us = clock_us
        self.opener = opener
        self.mav = mavlink2.MAVLink(_LinkWriter(self), srcSystem=system_id, srcComponent=component_id)
        self.parser = FrameParser(self.mav)
        self.timesync = TimeSync()
        self.counters = LinkCounters()
        self.connected = False
        self.peer: tuple[int, int] | None = None
        self.peer_is_autopilot = False
        self.error: str | None = None  # why the transport is closed, while it is
        self.transport: Transport | None = None
        self._opened_before = False
        self._last_seq: dict[tuple[int, int], int] = {}
        self._last_peer_heartbeat_us = 0
        self._next_heartbeat_us = 0
        self._next_timesync_us = 0
        self._next_open_us = 0
        self._window_received = 0.0
        self._window_lost = 0.0
        self._window_time_us = clock_us()
        self._open()

    def fileno(self) -> int | None:
        return self.transport.fileno() if self.transport is not None else None

    def send(self, msg: mavlink2.MAVLink_message) -> None:
        """Pack and send; never raises on a dead link (the message is counted in send_drops and dropped)."""
        self.mav.send(msg)

    def poll(self, timeout_s: float = 0.0) -> list[mavlink2.MAVLink_message]:
        """Wait up to timeout_s for input, read all there is and return every good message in order; send what is
        due (heartbeat, TIMESYNC requests); answer TIMESYNC requests; notice link loss and reopen."""
        now = self.clock_us()
        if self.transport is None and now >= self._next_open_us:
            self._open()
        self._wait(timeout_s)
        messages: list[mavlink2.MAVLink_message] = []
        if self.transport is not None:
            try:
                data = self.transport.read()
            except OSError as e:
                self._lose_transport(e)
                data = b""
            if data:
                self.counters.bytes_in += len(data)
                messages = self.parser.feed(data)
        now = self.clock_us()
        self._decay_quality_window(now)
        known = []
        for msg in messages:
            self.counters.packets_in += 1
            self._count_sequence((msg.get_srcSystem(), msg.get_srcComponent()), msg.get_seq())
            if not isinstance(msg, mavlink2.MAVLink_unknown):
                self._on_message(msg, now)
                known.append(msg)
        self._update_counters(now)
        self._send_due(now)
        return known

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()
            self.transport = None
        self.connected = False

    def _open(self) -> None:
        try:
            self.transport = self.opener(self.endpoint)
        except OSError as e:
            self.error = f"cannot open {self.endpoint}: {e}"
            self.counters.open_failures += 1
            self._next_open_us = self.clock_us() + REOPEN_PERIOD_US
            return
        if self._opened_before:
            self.counters.reconnects += 1
        self._opened_before = True
        self.error = None
        self._next_heartbeat_us = 0

    def _lose_transport(self, error: OSError) -> None:
        if self.transport is not None:
            self.transport.close()
        self.transport = None
        self.parser.discard_partial_frame()
        self._last_seq.clear()  # a replugged peer numbers its packets afresh
        self.error = f"{self.endpoint}: {error}"
        self._next_open_us = self.clock_us() + REOPEN_PERIOD_US
        self._set_disconnected()

    def _set_disconnected(self) -> None:
        if self.connected:
            self.counters.link_losses += 1
        self.connected = False

    def _wait(self, timeout_s: float) -> None:
        if timeout_s <= 0:
            return
        fd = self.fileno()
        if fd is None:
            time.sleep(timeout_s)
            return
        select.select([fd], [], [], timeout_s)

    def _write(self, frame: bytes) -> None:
        if self.transport is None:
            self.counters.send_drops += 1
            return
        try:
            sent = self.transport.write(frame)
        except OSError as e:
            self._lose_transport(e)
            sent = False
        if sent:
            self.counters.bytes_out += len(frame)
            self.counters.packets_out += 1
        else:
            self.counters.send_drops += 1

    def _on_message(self, msg: mavlink2.MAVLink_message, now: int) -> None:
        msg_id = msg.get_msgId()
        if msg_id == mavlink2.MAVLINK_MSG_ID_HEARTBEAT:
            self._on_heartbeat(msg, (msg.get_srcSystem(), msg.get_srcComponent()), now)
        elif msg_id == mavlink2.MAVLINK_MSG_ID_TIMESYNC:
            self._on_timesync(msg, now)

    def _count_sequence(self, source: tuple[int, int], seq: int) -> None:
        """Packets lost by sequence number per sender, as PX4's MavlinkReceiver::update_rx_stats (a repeated
        number is a duplicate, not 255 lost)."""
        last = self._last_seq.get(source)
        self._last_seq[source] = seq
        self._window_received += 1
        if last is None or seq == last:
            return
        lost = (seq - last - 1) & 0xFF
        self.counters.seq_gaps += lost
        self._window_lost += lost

    def _on_heartbeat(self, msg: mavlink2.MAVLink_message, source: tuple[int, int], now: int) -> None:
        if source == (self.system_id, self.component_id):
            return
        is_autopilot = msg.autopilot != mavlink2.MAV_AUTOPILOT_INVALID
        # the peer is kept while connected; an autopilot is preferred to any other component (a GCS, a companion)
        if not self.connected or source == self.peer or (is_autopilot and not self.peer_is_autopilot):
            self.peer = source
            self.peer_is_autopilot = is_autopilot
            self._last_peer_heartbeat_us = now
            self.connected = True

    def _on_timesync(self, msg: mavlink2.MAVLink_message, now: int) -> None:
        if msg.tc1 == 0:  # a request: answer at once with our time, as PX4's MavlinkTimesync does
            self.mav.timesync_send(max(1, now * 1000), msg.ts1)
        else:
            self.timesync.on_reply(msg.tc1, msg.ts1, now)

    def _decay_quality_window(self, now: int) -> None:
        decay = math.exp(-max(0, now - self._window_time_us) / (QUALITY_WINDOW_S * 1e6))
        self._window_time_us = now
        self._window_received *= decay
        self._window_lost *= decay

    def _update_counters(self, now: int) -> None:
        if self.connected and now - self._last_peer_heartbeat_us > self.link_timeout_us:
            self._set_disconnected()
        c = self.counters
        total = self._window_received + self._window_lost
        c.quality = self._window_received / total if self.connected and total > 0 else 0.0
        c.crc_errors = self.parser.crc_errors
        c.parse_errors = self.parser.parse_errors
        c.unknown_messages = self.parser.unknown_messages

    def _send_due(self, now: int) -> None:
        if self.transport is None:
            return
        if now >= self._next_heartbeat_us:
            self._next_heartbeat_us = now + HEARTBEAT_PERIOD_US
            self.mav.heartbeat_send(**self.heartbeat())
        if self.send_timesync and now >= self._next_timesync_us:
            self._next_timesync_us = now + TIMESYNC_PERIOD_US
            self.mav.timesync_send(0, self.timesync.request(now))
