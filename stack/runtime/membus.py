"""The bus of an in-process run (:mod:`stack.runtime.inprocess`): publishers and subscriptions in memory.

A publisher numbers its messages as :class:`stack.bus.topics.TopicPublisher` does (one sequence per
module shared by its topics, an index per topic, ``timestamp`` stamped when 0) and delivers each
message at once to every subscription of its topic, as the :class:`stack.bus.topics.Received` a Zenoh subscriber's
``poll`` would return. With ``wire=True`` each subscription gets its own copy decoded from the msgpack
bytes, as a subscriber process does (a message that does not decode is counted and dropped); with
``wire=False`` every subscription gets the publisher's object itself.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import TYPE_CHECKING

import msgspec

from stack.bus import keys
from stack.bus.topics import FLAG_LOCKSTEP_TIME, Received
from stack.msg.base import Message
from stack.msg.registry import message_type
from stack.runtime.inputs import InputBuffer

if TYPE_CHECKING:
    from stack.runtime.inprocess import InProcessRuntime

log = logging.getLogger("stack.bus")


class PublishedMessage(msgspec.Struct, frozen=True, gc=False):
    """One message as the bus carried it: the header of :data:`stack.bus.topics.HEADER` and the payload."""

    topic: str
    instance: int
    publisher_id: int
    index: int
    pub_time_us: int
    flags: int
    payload: bytes


class MemorySubscription:
    """One input's share of the bus (a :class:`stack.bus.topics.TopicSubscriber`'s place): each delivery goes to
    its ``sink`` at once, a data input's pending list (:class:`MemoryInput`) or the run's queue of triggered runs."""

    __slots__ = ("_decode", "decode_errors", "owner", "received", "sink", "suffix")

    foreign = 0
    schema_errors = 0

    def __init__(self, owner: InProcessRuntime, topic: str, instance: int, sink: Callable[[Received], None]) -> None:
        self.owner = owner
        self.suffix = keys.topic_suffix(topic, instance)
        self._decode = msgspec.msgpack.Decoder(message_type(topic)).decode
        self.sink = sink
        self.received = 0
        self.decode_errors = 0

    def deliver(self, item: Received) -> None:
        self.received += 1
        self.sink(item)

    def deliver_encoded(self, t: int, publisher_id: int, seq: int, data: bytes, index: int) -> None:
        try:
            msg = self._decode(data)
        except msgspec.DecodeError as e:
            self.decode_errors += 1
            if self.decode_errors == 1 or self.decode_errors % 1000 == 0:
                log.warning("%s: dropped malformed message (%d so far): %s", self.suffix, self.decode_errors, e)
            return
        self.deliver(Received(t, publisher_id, seq, msg, index))


class MemoryInput(InputBuffer):
    """A module's input on the memory bus: each delivery lands in its pending list at once, so there is nothing to
    pull, and refreshing an input that received nothing costs one test."""

    __slots__ = ()

    def __init__(self, bus: MemoryBus, owner: InProcessRuntime, topic: str, instance: int, queue_mode: bool) -> None:
        pending: list[Received] = []
        super().__init__(bus.subscribe(owner, topic, instance, pending.append), queue_mode)  # type: ignore[arg-type]
        self._pending = pending

    def pull(self) -> None:
        """Deliveries are already in the pending list."""

    def refresh(
        self, now: int, members: frozenset[int], trigger_publisher: int = -1, trigger_seq: int = 0
    ) -> None:
        if self._pending:
            self.promote_visible(now, trigger_publisher, trigger_seq, members)


class MemoryPublisher:
    """Publishes one topic of one module (a :class:`stack.bus.topics.TopicPublisher`'s place)."""

    __slots__ = ("_bus", "_encode", "_owner", "_subs", "count", "instance", "suffix", "topic")

    def __init__(self, bus: MemoryBus, owner: InProcessRuntime, topic: str, instance: int) -> None:
        self._bus = bus
        self._owner = owner
        self.topic = topic
        self.instance = instance
        self.suffix = keys.topic_suffix(topic, instance)
        self._encode = msgspec.msgpack.Encoder().encode
        self._subs = bus.subscriptions(topic, instance)
        self.count = 0

    def publish(self, msg: Message, now_us: int) -> None:
        if msg.timestamp == 0:
            msg.timestamp = now_us
        owner, bus = self._owner, self._bus
        owner.seq += 1
        self.count += 1
        seq, count, pid = owner.seq, self.count, owner.publisher_id
        data = self._encode(msg) if bus.wire or bus.record else b""
        if bus.record:
            bus.published.append(
                PublishedMessage(self.topic, self.instance, pid, count, now_us, FLAG_LOCKSTEP_TIME, data)
            )
        if bus.wire:
            for sub in self._subs:
                sub.deliver_encoded(now_us, pid, seq, data, count)
        else:
            item = Received(now_us, pid, seq, msg, count)
            for sub in self._subs:
                sub.deliver(item)


class MemoryBus:
    """The topics of one in-process run; ``published`` holds every message when ``record`` is set."""

    def __init__(self, *, wire: bool, record: bool) -> None:
        self.wire = wire
        self.record = record
        self.published: list[PublishedMessage] = []
        self._subscriptions: dict[tuple[str, int], list[MemorySubscription]] = {}

    def subscriptions(self, topic: str, instance: int) -> list[MemorySubscription]:
        """The live list of a topic's subscriptions (a publisher keeps it: later subscribers join it)."""
        return self._subscriptions.setdefault((topic, instance), [])

    def subscribe(
        self, owner: InProcessRuntime, topic: str, instance: int, sink: Callable[[Received], None]
    ) -> MemorySubscription:
        sub = MemorySubscription(owner, topic, instance, sink)
        self.subscriptions(topic, instance).append(sub)
        return sub

    def publisher(self, owner: InProcessRuntime, topic: str, instance: int) -> MemoryPublisher:
        return MemoryPublisher(self, owner, topic, instance)

    def unsubscribe_all(self, owner: InProcessRuntime) -> None:
        """A module that left the run receives nothing more."""
        for subs in self._subscriptions.values():
            subs[:] = [s for s in subs if s.owner is not owner]
