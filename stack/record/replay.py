"""Republishing a recording on a bus, so every tool sees it as live.

What subscribers see: each recorded message's exact payload, its recorded schema fingerprint,
publication time and header flags (a lockstep recording keeps its simulated times and lockstep
flag), on the same topic and instance, under the recorded vehicle. The publisher is the replay's
own bus node (publisher id random per replay, named ``replay`` in the graph), with its own
sequence and topic index numbers (1, 2, ... from the start of the replay); recorded publisher ids
are not reused, so a replay never impersonates a live module.

``stack replay`` publishes on a bus of its own (:mod:`stack.cli.replay_stack`), never on a running
stack's: modules there would mix the replayed messages with their own, and lockstep ones would meet
the recording's simulated times beside their run's.

Pacing follows the recording clock (each message's log time: the simulated time of a lockstep
recording, the receive time of a real-time one), scaled by the speed factor
(:mod:`stack.runtime.pacing`); speed 0 sends as fast as the bus accepts. Publishers block rather than
drop, so a slow subscriber slows the replay instead of losing messages.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable

import zenoh

from stack.bus import keys
from stack.bus.node import Node
from stack.bus.topics import HEADER
from stack.record.recorder import ChannelInfo, RecordedMessage, RecordingReader
from stack.record.selection import TopicSelection
from stack.runtime.pacing import MIN_SLEEP_S, Pacer

SETTLE_TIMEOUT_S = 1.0


class BusReplayer:
    """Publishes recorded messages on ``node``'s vehicle, one Zenoh publisher per topic instance."""

    def __init__(self, node: Node) -> None:
        self.node = node
        self.sent = 0
        self._pubs: dict[tuple[str, int], zenoh.Publisher] = {}
        self._index: dict[tuple[str, int], int] = {}

    def declare(self, channels: Iterable[ChannelInfo]) -> None:
        """Declare the publishers (and graph entries) up front, so subscribers' routes exist before sending."""
        for c in channels:
            self._publisher(c.topic, c.instance, c.type_name, c.fingerprint)

    def wait_for_subscribers(self, timeout_s: float = SETTLE_TIMEOUT_S) -> bool:
        """Wait until some subscriber matches a declared topic; False if none within the timeout."""
        deadline = time.monotonic() + timeout_s
        while True:
            if any(p.matching_status.matching for p in self._pubs.values()):
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)

    def _publisher(self, topic: str, instance: int, type_name: str, fp: int) -> zenoh.Publisher:
        pub = self._pubs.get((topic, instance))
        if pub is None:
            node = self.node
            pub = node.session.declare_publisher(
                keys.topic_key(node.vehicle, topic, instance),
                congestion_control=zenoh.CongestionControl.BLOCK,
                express=True,
            )
            self._pubs[(topic, instance)] = pub
            node.declare_token(
                keys.graph_token(node.vehicle, node.name, "pub", topic, instance, type_name or "unknown", fp)
            )
        return pub

    def publish(self, m: RecordedMessage) -> None:
        key = (m.topic, m.instance)
        pub = self._pubs.get(key)
        if pub is None:
            pub = self._publisher(m.topic, m.instance, type(m.msg).__name__ if m.msg is not None else "", m.fingerprint)
        node = self.node
        node.seq += 1
        index = self._index.get(key, 0) + 1
        self._index[key] = index
        header = HEADER.pack(m.fingerprint, node.publisher_id, node.seq, index, m.pub_time_us, m.flags, 0)
        pub.put(m.wire_payload(), attachment=header)
        self.sent += 1

    def close(self) -> None:
        for pub in self._pubs.values():
            pub.undeclare()
        self._pubs.clear()


def replay_pass(
    reader: RecordingReader,
    replayer: BusReplayer,
    clock: Pacer,
    *,
    topics: TopicSelection | None = None,
    progress: Callable[[int], None] | None = None,
    sleep: Callable[[float], None] = time.sleep,
) -> int:
    """One pass over the recording: send every selected message when it is due. Returns the count."""
    clock.restart()
    sent = 0
    pending = 0
    for m in reader.iter_messages(topics):
        delay = clock.delay_s(m.log_time_us)
        if delay > MIN_SLEEP_S:
            if progress is not None and pending:
                progress(pending)
                pending = 0
            sleep(delay)
        replayer.publish(m)
        sent += 1
        pending += 1
        if progress is not None and pending >= 256:
            progress(pending)
            pending = 0
    if progress is not None and pending:
        progress(pending)
    return sent
