"""Typed publishers and subscribers over Zenoh, with the stack's message header.

Every sample carries a 41-byte attachment (``HEADER``): the schema fingerprint of its type, the
publisher id, a per-publisher sequence number shared by all its topics, the index of the message
on its topic (1, 2, ... per publisher), the publication time (µs), flags (bit 0: the time is
lockstep simulated time) and the lockstep run's random id (0 outside lockstep). The fingerprint lets
a subscriber built from a different definition detect the mismatch and drop the sample instead of
mis-decoding it; the sequence number, topic index and time make lockstep deterministic; the run id
lets a lockstep module tell its run's messages from any other sender claiming a lockstep time
(counted as ``foreign`` and dropped).

On the same-host fast path (:mod:`stack.fastpath`) a publisher writes each message into its shared-
memory ring and puts it on Zenoh only while something outside the fast path subscribes to the topic;
a topic nobody reads is not even encoded.
"""

from __future__ import annotations

import collections
import logging
import struct
import threading
from typing import TYPE_CHECKING, Any

import msgspec
import zenoh

from stack.bus import keys
from stack.msg.base import Message
from stack.msg.registry import fingerprint

if TYPE_CHECKING:
    from stack.bus.node import Node
    from stack.fastpath.ring import RingWriter

HEADER = struct.Struct("<QIQIqBQ")
FLAG_LOCKSTEP_TIME = 1
# A probe carries no message: a publisher sends probes at start-up so each subscriber can tell that
# the publisher's samples reach it (see stack.runtime.runner: the lockstep start-up sync).
FLAG_PROBE = 2
MAX_SAMPLE_BYTES = 48_000
"""The largest sample (message and header) the bus carries. Zenoh's low-latency transport, which the sessions
of a stack use (stack.bus.config), sends a message in one batch, never in fragments, and a larger one is lost
without a word (on 127.0.0.1 just over 49 kB arrived, between peers and through the router; the rest is margin).
A publisher refuses a larger message (:class:`MessageTooLarge`) rather than lose it."""


class MessageTooLarge(ValueError):
    """A message larger than the bus carries (:data:`MAX_SAMPLE_BYTES`); nothing was published."""


log = logging.getLogger("stack.bus")

# How long a blocking receive waits between looks at its queue (a signal handler runs in between).
RECV_WAKE_S = 0.5
# The samples a keep-last subscription's ring holds until its owner decodes them: a burst of garbage this long
# between two looks is still counted in full.
RING_SAMPLES = 1024


class Received(msgspec.Struct, frozen=True, gc=False):
    """One message as a subscription delivers it, with what the lockstep needs to know of its publication."""

    time_us: int
    """When it was published, in lockstep (simulated) time; -1 when published on the wall clock."""
    publisher: int
    """The publisher's id (:func:`stack.bus.node.stable_publisher_id`)."""
    seq: int
    """The publisher's sequence number, one sequence for all its topics."""
    msg: Any
    index: int
    """Its index among the publisher's messages on this topic (1, 2, ...)."""


class TopicPublisher:
    """Publishes one topic. On the fast path, ``fast`` is its ring and ``fast_read`` whether any process reads it."""

    __slots__ = (
        "_node",
        "_pub",
        "count",
        "encoder",
        "fast",
        "fast_read",
        "fingerprint",
        "instance",
        "key",
        "msg_type",
        "suffix",
        "topic",
    )

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
        self.fast: RingWriter | None = None
        self.fast_read = False
        # A droppable message goes below Zenoh's default priority: behind a slow link its queue is full, and a
        # message that may not be dropped (a query's final reply, Zenoh's own) waiting there for room holds up the
        # router it passes, with every message of the vehicle, for up to the 5 s after which Zenoh closes the link.
        self._pub = node.session.declare_publisher(
            self.key,
            congestion_control=zenoh.CongestionControl.BLOCK if reliable else zenoh.CongestionControl.DROP,
            priority=zenoh.Priority.DATA if reliable else zenoh.Priority.DATA_LOW,
            express=True,
        )

    def publish(self, msg: Message, now_us: int | None = None) -> None:
        node = self._node
        if now_us is None:
            now_us = node.now_us()
        if msg.timestamp == 0:
            msg.timestamp = now_us
        fast = self.fast
        outside = fast is None or bool(fast.words[fast.zenoh_word])
        data = self.encoder.encode(msg) if outside or self.fast_read else b""
        if outside and len(data) + HEADER.size > MAX_SAMPLE_BYTES:
            # Refused before it is counted: a subscriber never sees a gap in a publisher's sequence.
            raise MessageTooLarge(
                f"{self.topic}: a message of {len(data) + HEADER.size} bytes, more than the {MAX_SAMPLE_BYTES} "
                "one message on the bus may have"
            )
        node.seq += 1
        self.count += 1
        if fast is not None and self.fast_read:
            fast.write(data, self.count, now_us, node.seq)
        if outside:
            self._put(data, now_us)
        node.on_published(self)

    def _put(self, data: bytes, now_us: int) -> None:
        node = self._node
        header = HEADER.pack(
            self.fingerprint, node.publisher_id, node.seq, self.count, now_us, node.header_flags, node.run_id
        )
        self._pub.put(data, attachment=header)

    def probe(self) -> None:
        """Send a probe (not a message: subscribers note the publisher and deliver nothing)."""
        node = self._node
        header = HEADER.pack(self.fingerprint, node.publisher_id, 0, 0, 0, FLAG_PROBE, node.run_id)
        self._pub.put(b"", attachment=header)

    def matching(self) -> bool:
        """Whether any subscriber is known for this topic."""
        return self._pub.matching_status.matching

    def undeclare(self) -> None:
        self._pub.undeclare()


class TopicSubscriber:
    """A subscription drained by the owner's loop: ``recv`` blocks (GIL released), ``poll`` never does.

    Three ways to queue what arrives:

    - FIFO (the default): Zenoh queues up to ``capacity`` samples (its receiving thread waits when they are
      full); the owner's thread decodes them as it takes them.
    - ``callback``: Zenoh's thread decodes each sample as it arrives and queues the valid ones in ``arrived``
      (at most ``capacity``, the oldest dropped) and sets an event a thread can wait on with others: a loop
      that polls many inputs which almost never receive anything (a fast-path module's outside messages) then
      only looks at an empty deque, and every malformed sample is counted, however many arrive between two
      looks.
    - ``keep_last``: Zenoh's thread queues the samples in a ring of RING_SAMPLES (the oldest dropped) and never
      takes the GIL; the owner's thread decodes them into ``arrived`` (the newest ``capacity`` valid ones) as
      it polls, and its ``recv`` waits on Zenoh's channel. For a real-time module that waits on one trigger
      alone: decoded in Zenoh's thread, each message took the GIL there, then woke the module's thread, which
      waited for the GIL in turn (a fifth of an idle real-time stack's CPU).

    Counters of a withdrawn subscriber stay in its node's (:meth:`stack.bus.node.Node.drop_counts`).
    """

    __slots__ = (
        "_arrival",
        "_decoder",
        "_node",
        "_ring",
        "_run_id",
        "_sub",
        "_warned",
        "arrived",
        "decode_errors",
        "fingerprint",
        "foreign",
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
        callback: bool = False,
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
        self.foreign = 0
        self._run_id = node.run_id
        self._warned = False
        self.arrived: collections.deque[Received] | None = None
        self._arrival = threading.Event()
        self._ring = keep_last and not callback
        self._node = node
        node.live_subscribers.add(self)
        if callback:
            self.arrived = collections.deque(maxlen=capacity)
            # In Zenoh's receiving thread (a message from this process's session: in the publishing thread), not in a
            # Python thread of the subscription's own (zenoh-python's default), which each message would wake: with
            # that, the modules of a real-time hover in two shared processes took a quarter more CPU.
            on_sample = zenoh.handlers.Callback(self._on_sample, indirect=False)
            self._sub = node.session.declare_subscriber(self.key, on_sample)
        elif keep_last:
            self.arrived = collections.deque(maxlen=capacity)
            self._sub = node.session.declare_subscriber(self.key, zenoh.handlers.RingChannel(RING_SAMPLES))
        else:
            self._sub = node.session.declare_subscriber(self.key, zenoh.handlers.FifoChannel(capacity))

    def _on_sample(self, sample: zenoh.Sample) -> None:
        item = self._decode(sample)
        if item is not None and self.arrived is not None:
            self.arrived.append(item)
            self._arrival.set()

    def _decode(self, sample: zenoh.Sample) -> Received | None:
        attachment = sample.attachment
        if attachment is None:
            self._reject_schema("no stack header (not published through the stack runtime)")
            return None
        raw = attachment.to_bytes()
        if len(raw) != HEADER.size:
            self._reject_schema(f"malformed header of {len(raw)} bytes")
            return None
        fp, pub_id, seq, index, pub_time, flags, run = HEADER.unpack(raw)
        if self._run_id and flags & (FLAG_LOCKSTEP_TIME | FLAG_PROBE) and run != self._run_id:
            self.foreign += 1
            if self.foreign == 1 or self.foreign % 1000 == 0:
                log.warning("%s: dropped a lockstep message from outside this run (%d so far)", self.key, self.foreign)
            return None
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
        return Received(pub_time if flags & FLAG_LOCKSTEP_TIME else -1, pub_id, seq, msg, index)

    def _reject_schema(self, why: str) -> None:
        self.schema_errors += 1
        if not self._warned or self.schema_errors % 1000 == 0:
            self._warned = True
            log.error("%s: schema mismatch, dropped (%d so far): %s", self.key, self.schema_errors, why)

    def _take_ring(self) -> None:
        """Decode what the ring holds into ``arrived`` (keep-last)."""
        arrived, sub = self.arrived, self._sub
        assert arrived is not None
        sample = sub.try_recv()
        while sample is not None:
            item = self._decode(sample)
            if item is not None:
                arrived.append(item)
            sample = sub.try_recv()

    def poll(self) -> Received | None:
        """Next valid message, or None if none is waiting."""
        if self._ring:
            self._take_ring()
        if self.arrived is not None:
            return self.arrived.popleft() if self.arrived else None
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
        arrived = self.arrived
        if self._ring:
            assert arrived is not None
            self._take_ring()
            while not arrived:
                item = self._decode(self._sub.recv())
                if item is not None:
                    arrived.append(item)
                    self._take_ring()
            return arrived.popleft()
        if arrived is not None:
            while True:
                if arrived:
                    return arrived.popleft()
                self._arrival.clear()
                if not arrived:
                    self._arrival.wait(RECV_WAKE_S)
        sub = self._sub
        while True:
            item = self._decode(sub.recv())
            if item is not None:
                return item

    def share_arrival(self, event: threading.Event) -> None:
        """Set ``event`` on each message queued, in place of this subscriber's own: one event for the subscriptions
        that a thread waits on together (a ``callback`` one; it is then drained with ``poll``)."""
        if self.arrived is None or self._ring:
            raise TypeError(f"{self.key}: only a callback subscriber can share its arrivals")
        self._arrival = event

    def wait(self, timeout: float) -> None:
        """Block until a message has arrived or ``timeout`` (s) has passed (a ``callback`` one)."""
        if self.arrived is None or self._ring:
            raise TypeError(f"{self.key}: only a callback subscriber can wait for a message with a timeout")
        self._arrival.clear()
        if not self.arrived:
            self._arrival.wait(timeout)

    def undeclare(self) -> None:
        self._sub.undeclare()
        self._node.retire(self)
