"""Every record of a fast-path run, for a passive reader of all topics (the recorder).

The reader takes each ring's records older than the current step (so it never reads a step still
being written), copies their payloads out, and then marks how far it has read: when a lossless reader
falls far behind, lockstep time waits for it instead of letting the rings overwrite what it has not
read yet.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import attrgetter

import msgspec

from stack.fastpath.attach import Attachment
from stack.fastpath.layout import H_NOW, H_TOPOLOGY, P_FINGERPRINT, S_READ_TIME
from stack.fastpath.ring import RingReader
from stack.fastpath.topology import Topology


class RingRecord(msgspec.Struct, frozen=True, gc=False):
    """A record copied out of a ring, with what a recording keeps of it."""

    topic: str
    """``topic/instance``."""
    fingerprint: int
    """The schema fingerprint of its message type."""
    publisher_id: int
    index: int
    """Its index on its topic for its publisher."""
    time_us: int
    """When it was published (simulated µs)."""
    payload: bytes


RecordSink = Callable[[RingRecord], None]
_publication_time = attrgetter("time_us")


class AllTopicsReader:
    def __init__(self, att: Attachment) -> None:
        self.att = att
        self.region = att.region
        self._readers: list[tuple[RingReader, str]] = []
        self._topology_seen = -1
        self.publisher_ids: frozenset[int] = frozenset()

    @property
    def lost(self) -> int:
        return sum(r.lost for r, _ in self._readers)

    def _refresh(self) -> None:
        """Read the rings of every process admitted so far: one that left still has records to read."""
        w = self.region.words
        if w[H_TOPOLOGY] == self._topology_seen:
            return
        topo = Topology(self.region)
        self._topology_seen = topo.generation
        self.publisher_ids = topo.publisher_ids
        known = {(r.slot, r.entry) for r, _ in self._readers}
        for p in topo.participants:
            if p.slot == self.att.slot:
                continue
            for pub in self.region.publications(p.slot):
                if (p.slot, self.region.pub_word(p.slot, pub.index, 0)) not in known:
                    self._readers.append((RingReader(self.region, p.slot, pub.index, p.publisher_id), pub.name))

    def read(self, sink: RecordSink, final: bool = False) -> int:
        """Hand every record older than the current step (every record at all if ``final``) to ``sink``,
        in order of publication time (each ring is in that order already: they are merged)."""
        self._refresh()
        w = self.region.words
        now = int(w[H_NOW])
        horizon = 1 << 63 if final else now
        records: list[RingRecord] = []
        for r, suffix in self._readers:
            records += self._take(r, suffix, horizon)
        records.sort(key=_publication_time)  # stable: a merge of the rings, each in order already
        for record in records:
            sink(record)
        w[self.region.slot_word(self.att.slot, S_READ_TIME)] = now
        return len(records)

    def _take(self, r: RingReader, suffix: str, horizon: int) -> list[RingRecord]:
        taken = r.take_new(horizon)
        if not taken:
            return []
        fingerprint = int(self.region.words[r.entry + P_FINGERPRINT])
        return [RingRecord(suffix, fingerprint, r.publisher_id, h.index, h.time_us, payload) for h, payload in taken]
