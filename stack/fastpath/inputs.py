"""A module's subscriptions on the fast path: the rings of the run's publishers, plus Zenoh from outside.

The visibility rules are those of :mod:`stack.runtime.inputs` (:func:`~stack.runtime.inputs.visible`): a run
at time ``t`` triggered by a record of publisher ``P`` sees every record published before ``t``, and the records
``P`` published at ``t`` before its trigger; records other members publish at ``t`` wait for the next run.
Messages from outside the run arrive over Zenoh and are seen at once; samples on Zenoh from the run's own publishers
(put there for outside subscribers) are duplicates of ring records and are skipped.
"""

from __future__ import annotations

import logging
from typing import NamedTuple

import msgspec

from stack.bus.topics import Received, TopicSubscriber
from stack.fastpath.layout import Region, topic_hash
from stack.fastpath.ring import RingReader
from stack.runtime.inputs import InputBuffer, visible

log = logging.getLogger("stack.fastpath")

class Source(NamedTuple):
    """A publisher of a topic in the run, as a reader finds its ring."""

    slot: int
    publication: int
    """The index of the topic among the slot's publications."""
    publisher_id: int


class FastInput(InputBuffer):
    """One subscribed topic of a fast-path process (the module API sees an :class:`InputBuffer`)."""

    __slots__ = (
        "_buckets",
        "_decoder",
        "_fast_decode_errors",
        "_fast_received",
        "_inside",
        "every_us",
        "hash",
        "keep",
        "readers",
        "region",
    )

    def __init__(self, region: Region, sub: TopicSubscriber, queue_mode: bool, keep: int = 0) -> None:
        """``keep``: a queue that may lose messages (a passive module's) takes at most the newest ``keep``
        records of each publisher per refresh, like a ring buffer of that size dropping its oldest.
        ``every_us`` (set by a module that decimates anyway, the plot bridge): a queue takes only the
        first record of each publisher in each period-aligned interval, and never decodes the others."""
        super().__init__(sub, queue_mode)
        self.keep = keep
        self.every_us = 0
        self._buckets: dict[int, int] = {}  # publisher slot → interval of its last record taken
        self.hash = topic_hash(sub.suffix)
        self.readers: list[RingReader] = []
        self._decoder = msgspec.msgpack.Decoder(sub.msg_type)
        self._inside: frozenset[int] = frozenset()
        self._fast_received = 0
        self._fast_decode_errors = 0
        self.region = region

    # -- counters (heartbeat) ----------------------------------------------------------------------

    @property
    def received(self) -> int:
        return self._fast_received + self.sub.received

    @property
    def decode_errors(self) -> int:
        return self._fast_decode_errors + self.sub.decode_errors

    @property
    def ring_decode_errors(self) -> int:
        return self._fast_decode_errors

    @property
    def lost(self) -> int:
        return sum(r.lost for r in self.readers)

    # -- topology ----------------------------------------------------------------------------------

    def resolve(self, sources: list[Source], inside: frozenset[int], since: int) -> None:
        """Read from ``sources`` too; ``inside`` are the publisher ids whose Zenoh samples are duplicates (the topic's
        publishers in the run: a member's sample of a topic it has no ring of is heard, and judged, as from outside).

        A reader kept from before keeps its place, including one of a publisher that has left (its last
        records are still messages); a new queue reader starts with the records published at or after
        ``since`` (when this process was admitted), so a process admitted late does not replay old messages.
        """
        known = {(r.slot, r.entry) for r in self.readers}
        for slot, pub, publisher_id in sources:
            if (slot, self.region.pub_word(slot, pub, 0)) in known:
                continue
            reader = RingReader(self.region, slot, pub, publisher_id)
            if self.queue_mode:
                reader.taken = first_at_or_after(reader, since) - 1
            self.readers.append(reader)
        self._inside = inside

    def from_inside(self, item: Received) -> bool:
        """Whether a Zenoh sample is one of the run's own records, put on Zenoh for an outside subscriber (a
        ground-station link, ``stack topic echo``): it carries the run's lockstep time (only the run's members
        stamp it, and samples of other runs are dropped on arrival) or comes from a publisher of the topic in it.
        The time tells even before this process has learnt who is in the run."""
        return item.time_us >= 0 or item.publisher in self._inside

    # -- reading -----------------------------------------------------------------------------------

    def refresh(
        self, now: int, members: frozenset[int] = frozenset(), trigger_publisher: int = -1, trigger_seq: int = 0
    ) -> None:
        """Take in what a run at ``now`` may see (see the module docstring), then Zenoh's outside messages (the
        rings are the run's members')."""
        for r in self.readers:
            count = r.words[r.count_word]
            if count > r.taken:
                if self.queue_mode:
                    self._take_all(r, count, now, trigger_publisher, trigger_seq)
                else:
                    self._take_newest(r, count, now, trigger_publisher, trigger_seq)
        if self.sub.arrived:
            self._take_outside(now)

    def take_in_everything(self) -> None:
        self.refresh(1 << 63)

    def _take_newest(self, r: RingReader, count: int, now: int, trigger_publisher: int, trigger_seq: int) -> None:
        n = count
        floor = max(r.taken, count - r.records)
        while n > floor:
            head = r.header(n)
            if head is None:
                return
            t, seq = head.time_us, head.seq
            if visible(t, r.publisher_id, seq, now, trigger_publisher, trigger_seq):
                self._decode(r, n, head.offset, t, seq)
                r.taken = n
                return
            n -= 1

    def _take_all(self, r: RingReader, count: int, now: int, trigger_publisher: int, trigger_seq: int) -> None:
        n = r.oldest_readable(count)
        if self.keep and count - n >= self.keep:
            n = count - self.keep + 1
        while n <= count:
            head = r.header(n)
            if head is None:
                r.lost += 1
            else:
                t, seq = head.time_us, head.seq
                if not visible(t, r.publisher_id, seq, now, trigger_publisher, trigger_seq):
                    return
                if self.every_us:
                    bucket = t // self.every_us
                    if self._buckets.get(r.slot) == bucket:
                        r.taken = n
                        n += 1
                        continue
                    self._buckets[r.slot] = bucket
                self._decode(r, n, head.offset, t, seq)
            r.taken = n
            n += 1

    def _decode(self, r: RingReader, n: int, rec: int, t: int, seq: int) -> None:
        try:
            msg = self._decoder.decode(r.payload(rec))
        except msgspec.DecodeError:
            msg = None
        if not r.still(n, rec):
            r.lost += 1
            return
        if msg is None:
            self._fast_decode_errors += 1
            if self._fast_decode_errors == 1:
                log.error("%s: undecodable fast-path record from slot %d", self.sub.suffix, r.slot)
            return
        self._fast_received += 1
        self._accept((t, r.publisher_id, seq), msg)

    def _take_outside(self, now: int) -> None:
        arrived = self.sub.arrived
        while arrived:
            item = arrived.popleft()
            if not self.from_inside(item):
                self._accept((now, item.publisher, item.seq), item.msg)


def first_at_or_after(reader: RingReader, time_us: int) -> int:
    """The first record of ``reader``'s ring published at or after ``time_us`` (count + 1 if none)."""
    count = reader.count
    n = count
    while n > max(0, count - reader.records):
        head = reader.header(n)
        if head is None or head.time_us < time_us:
            break
        n -= 1
    return n + 1
