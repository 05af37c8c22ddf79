"""Typed publishers and subscribers over Zenoh, with the stack's message header.

Every sample carries a 33-byte attachment (``HEADER``): the schema fingerprint of its type, the
publisher id, a per-publisher sequence number shared by all its topics, the index of the message
on its topic (1, 2, ... per publisher), the publication time (µs) and flags (bit 0: the time is
lockstep simulated time). The fingerprint lets a subscriber built from a different definition detect
the mismatch and drop the sample instead of mis-decoding it; the sequence number, topic index and
time make lockstep deterministic.
"""

from __future__ import annotations

import logging
import struct
from typing import TYPE_CHECKING, Any

import msgspec
import zenoh

from stack.bus import keys
from stack.msg.base import Message
from stack.msg.registry import fingerprint

if TYPE_CHECKING:
    from stack.bus.node import Node

HEADER = struct.Struct("<QIQIqB")
FLAG_LOCKSTEP_TIME = 1
# A probe carries no message: a publisher sends probes at start-up so each subscriber can tell that
# the publisher's samples reach it (see stack.runtime.runner: the lockstep start-up sync).
FLAG_PROBE = 2


log = logging.getLogger("stack.bus")

# Diagnostics that nothing in the control path consumes: in real time these may be dropped under
# load rather than stall their publisher. Everything else (commands and state) blocks.
TELEMETRY_TOPICS = frozenset(
    {"rate_ctrl_status", "vehicle_local_position_setpoint", "sim_groundtruth", "actuator_outputs", "parameter_update"}
)

# (publication time µs — or -1 when not lockstep time —, publisher id, publisher sequence, message,
#  index of the message on its topic for that publisher)
Received = tuple[int, int, int, Any, int]


class TopicPublisher:
    __slots__ = ("_node", "_pub", "count", "encoder", "fingerprint", "instance", "key", "msg_type", "suffix", "topic")

    def __init__(self, node: Node, topic: str, instance: int, msg_type: type[Message], reliable: bool) -> None:
        self._node = node
        self.topic = topic
        self.instance = instance
        self.msg_type = msg_type
        self.key = keys.topic_key(node.vehicle, topic, instance)
        self.suffix = keys.topic_suffix(topic, instance)
        self.fingerprint = fingerprint(msg_type)
        self.encoder = msgspec.msgpack.Encoder()
        self.count = 0
        self._pub = node.session.declare_publisher(
            self.key,
            congestion_control=zenoh.CongestionControl.BLOCK if reliable else zenoh.CongestionControl.DROP,
            express=True,
        )

    def publish(self, msg: Message, now_us: int | None = None) -> None:
        node = self._node
        if now_us is None:
            now_us = node.now_us()
        if msg.timestamp == 0:
            msg.timestamp = now_us
        node.seq += 1
        self.count += 1
        header = HEADER.pack(self.fingerprint, node.publisher_id, node.seq, self.count, now_us, node.header_flags)
        self._pub.put(self.encoder.encode(msg), attachment=header)
        node.on_published(self)

    def probe(self) -> None:
        """Send a probe (not a message: subscribers note the publisher and deliver nothing)."""
        node = self._node
        self._pub.put(b"", attachment=HEADER.pack(self.fingerprint, node.publisher_id, 0, 0, 0, FLAG_PROBE))

    def matching(self) -> bool:
        """Whether any subscriber is known for this topic."""
        return self._pub.matching_status.matching

    def undeclare(self) -> None:
        self._pub.undeclare()


class TopicSubscriber:
    """A subscription drained by the owner's loop: ``recv`` blocks (GIL released), ``poll`` never does."""

    __slots__ = (
        "_decoder",
        "_sub",
        "_warned",
        "decode_errors",
        "fingerprint",
        "instance",
        "key",
        "msg_type",
        "probed_by",
        "received",
        "schema_errors",
        "suffix",
        "topic",
    )

    def __init__(
        self,
        node: Node,
        topic: str,
        instance: int,
        msg_type: type[Message],
        capacity: int = 256,
        keep_last: bool = False,
    ) -> None:
        self.topic = topic
        self.instance = instance
        self.msg_type = msg_type
        self.key = keys.topic_key(node.vehicle, topic, instance)
        self.suffix = keys.topic_suffix(topic, instance)
        self.fingerprint = fingerprint(msg_type)
        self._decoder = msgspec.msgpack.Decoder(msg_type)
        self.received = 0
        self.probed_by: set[int] = set()
        self.decode_errors = 0
        self.schema_errors = 0
        self._warned = False
        handler = zenoh.handlers.RingChannel(capacity) if keep_last else zenoh.handlers.FifoChannel(capacity)
        self._sub = node.session.declare_subscriber(self.key, handler)

    def _decode(self, sample: zenoh.Sample) -> Received | None:
        attachment = sample.attachment
        if attachment is None:
            self._reject_schema("no stack header (not published through the stack runtime)")
            return None
        raw = attachment.to_bytes()
        if len(raw) != HEADER.size:
            self._reject_schema(f"malformed header of {len(raw)} bytes")
            return None
        fp, pub_id, seq, index, pub_time, flags = HEADER.unpack(raw)
        if flags & FLAG_PROBE:
            self.probed_by.add(pub_id)
            return None
        if fp != self.fingerprint:
            mine = f"{self.msg_type.__name__} {self.fingerprint:016x}"
            self._reject_schema(f"publisher {pub_id:08x} sends schema {fp:016x}, this subscriber expects {mine}")
            return None
        try:
            msg = self._decoder.decode(sample.payload.to_bytes())
        except msgspec.DecodeError as e:
            self.decode_errors += 1
            if self.decode_errors == 1 or self.decode_errors % 1000 == 0:
                log.warning("%s: dropped malformed message (%d so far): %s", self.key, self.decode_errors, e)
            return None
        self.received += 1
        return (pub_time if flags & FLAG_LOCKSTEP_TIME else -1, pub_id, seq, msg, index)

    def _reject_schema(self, why: str) -> None:
        self.schema_errors += 1
        if not self._warned or self.schema_errors % 1000 == 0:
            self._warned = True
            log.error("%s: schema mismatch, dropped (%d so far): %s", self.key, self.schema_errors, why)

    def poll(self) -> Received | None:
        """Next valid message, or None if none is waiting."""
        sub = self._sub
        while True:
            sample = sub.try_recv()
            if sample is None:
                return None
            item = self._decode(sample)
            if item is not None:
                return item

    def recv(self) -> Received:
        """Block until the next valid message (Ctrl-C and signal handlers still run)."""
        sub = self._sub
        while True:
            item = self._decode(sub.recv())
            if item is not None:
                return item

    def undeclare(self) -> None:
        self._sub.undeclare()
