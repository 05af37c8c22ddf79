"""Per-(publisher, topic) rings of fixed-size records in the fast-path region.

Record ``n`` (1, 2, ...) of a ring sits in record slot ``n % records``:

    word 0  n, or 0 while the record is being written
    word 1  the message's index on its topic for this publisher (the stack header's ``index``)
    word 2  publication time (simulated µs)
    word 3  the publisher's sequence number (the stack header's ``seq``)
    word 4  payload length
    then the msgpack payload

The publisher writes word 0 last and then the ring's count (in its counter block), so a reader that
sees the count sees the record. A reader checks word 0 again after decoding: if it changed, the
record was overwritten meanwhile (the reader fell more than a ring behind) and is counted as lost.
A message too large for its record replaces the ring by one with larger records (the entry's
generation tells readers to look again); rings are never freed, so a reader never reads unmapped
or reused memory.
"""

from __future__ import annotations

import os

import msgspec

from stack.fastpath.layout import (
    C_PUBS,
    MAX_PUBS,
    P_FINGERPRINT,
    P_GENERATION,
    P_NAME,
    P_RECORD_BYTES,
    P_RECORDS,
    P_RING,
    P_TOPIC,
    P_ZENOH,
    S_HEAP_USED,
    S_NPUBS,
    Region,
    topic_hash,
)

RECORDS = 256
MIN_RECORDS = 16
RING_BYTES = 256 << 10  # records beyond RECORDS × MIN_RECORD_BYTES mean fewer records, down to MIN_RECORDS
RECORD_HEADER = 40
MIN_RECORD_BYTES = 256


def record_bytes_for(payload: int) -> int:
    """A power of two with room for the header and twice ``payload`` (messages vary a little in size)."""
    size = MIN_RECORD_BYTES
    while size < RECORD_HEADER + 2 * payload:
        size *= 2
    return size


def records_for(record_bytes: int) -> int:
    """Records per ring: as many as a reader may need to lag by, fewer for large messages (rarely sent)."""
    return max(MIN_RECORDS, min(RECORDS, RING_BYTES // record_bytes))


class RingFull(RuntimeError):
    """A slot's heap has no room left for another ring."""


def allocate(region: Region, slot: int, size: int) -> int:
    """Bytes from the slot's heap (its bump pointer survives restarts, so rings are never reused)."""
    w = region.words
    used_word = region.slot_word(slot, S_HEAP_USED)
    start, capacity = region.heap(slot)
    used = int(w[used_word])
    if used + size > capacity:
        raise RingFull(f"fast-path heap of slot {slot} full ({capacity >> 20} MiB): too many or too large topics")
    w[used_word] = used + size
    return start + used


def declare_publication(region: Region, slot: int, suffix: str, fingerprint: int, sample_payload: int) -> int:
    """This slot's publication of ``suffix``: the entry a previous process of the slot made, else a new one.

    Keeping the entry across restarts keeps the ring and its count, so readers never see a topic's
    records start again from 1.
    """
    w = region.words
    h = topic_hash(suffix)
    npubs = int(w[region.slot_word(slot, S_NPUBS)])
    for j in range(npubs):
        if w[region.pub_word(slot, j, P_TOPIC)] == h:
            w[region.pub_word(slot, j, P_FINGERPRINT)] = fingerprint
            return j
    if npubs >= MAX_PUBS:
        raise RingFull(f"a module may publish at most {MAX_PUBS} topics on the fast path")
    record = record_bytes_for(sample_payload)
    records = records_for(record)
    ring = allocate(region, slot, records * record)
    entry = region.pub_word(slot, npubs, 0)
    w[entry + P_TOPIC] = h
    w[entry + P_FINGERPRINT] = fingerprint
    w[entry + P_RING] = ring
    w[entry + P_RECORDS] = records
    w[entry + P_RECORD_BYTES] = record
    w[entry + P_GENERATION] = 1
    w[entry + P_ZENOH] = 0
    region.write_text(entry + P_NAME, suffix)
    w[region.slot_word(slot, S_NPUBS)] = npubs + 1
    return npubs


class RingWriter:
    """The publisher's end of one ring. ``wake`` lists (slot, eventfd) of the members the topic triggers.

    Writing a record only notes whom to wake in ``wakes`` (shared by the process's writers); the process
    wakes them all when its run is over (:func:`wake_all`), so a member woken by an early message never
    preempts the rest of the run that sent it.
    """

    __slots__ = (
        "_b",
        "count_word",
        "entry",
        "payload_max",
        "record",
        "records",
        "region",
        "ring",
        "slot",
        "topic",
        "wake",
        "wakes",
        "words",
        "zenoh_word",
    )

    def __init__(self, region: Region, slot: int, pub: int, wakes: set[int]) -> None:
        self.region = region
        self.slot = slot
        self.words = region.words
        self._b = region.bytes
        self.entry = region.pub_word(slot, pub, 0)
        self.topic = int(self.words[self.entry + P_TOPIC])
        self.zenoh_word = self.entry + P_ZENOH
        self.count_word = region.counter_word(slot, C_PUBS + pub)
        self.wake: tuple[tuple[int, int], ...] = ()
        self.wakes = wakes
        self._load()

    def _load(self) -> None:
        w, e = self.words, self.entry
        self.ring = int(w[e + P_RING])
        self.records = int(w[e + P_RECORDS])
        self.record = int(w[e + P_RECORD_BYTES])
        self.payload_max = self.record - RECORD_HEADER

    @property
    def count(self) -> int:
        return int(self.words[self.count_word])

    def zenoh_wanted(self) -> bool:
        return self.words[self.zenoh_word] != 0

    def write(self, data: bytes, index: int, time_us: int, seq: int) -> None:
        """Append a record and note the members this topic triggers."""
        w = self.words
        n = w[self.count_word] + 1
        size = len(data)
        if size > self.payload_max:
            self._grow(size, n)
        rec = self.ring + (n % self.records) * self.record
        q = rec >> 3
        w[q] = 0
        self._b[rec + RECORD_HEADER : rec + RECORD_HEADER + size] = data
        w[q + 1] = index
        w[q + 2] = time_us
        w[q + 3] = seq
        w[q + 4] = size
        w[q] = n
        w[self.count_word] = n
        for _, fd in self.wake:
            self.wakes.add(fd)

    def _grow(self, size: int, next_n: int) -> None:
        """Move to a ring of larger records, carrying over the records still in the old one."""
        record = record_bytes_for(size)
        records = records_for(record)
        ring = allocate(self.region, self.slot, records * record)
        w, b = self.words, self._b
        for n in range(max(1, next_n - min(records, self.records) + 1), next_n):
            old = self.ring + (n % self.records) * self.record
            if w[old >> 3] != n:
                continue
            length = int(w[(old >> 3) + 4])
            new = ring + (n % records) * record
            b[new : new + RECORD_HEADER + length] = b[old : old + RECORD_HEADER + length]
        e = self.entry
        w[e + P_RING] = ring
        w[e + P_RECORDS] = records
        w[e + P_RECORD_BYTES] = record
        w[e + P_GENERATION] = w[e + P_GENERATION] + 1
        self._load()


def wake_all(wakes: set[int]) -> None:
    """Wake the processes that records written since the last call trigger."""
    for fd in wakes:
        os.eventfd_write(fd, 1)
    wakes.clear()


class RecordHeader(msgspec.Struct, frozen=True, gc=False):
    """What a record's header words say, and where the record is."""

    index: int
    """The message's index on its topic for its publisher."""
    time_us: int
    """When it was published (simulated µs)."""
    seq: int
    """The publisher's sequence number."""
    offset: int
    """Byte offset of the record in the region (for ``payload`` and ``still``)."""


class RingReader:
    """A subscriber's view of one publisher's ring of a topic.

    ``taken`` is the last record the subscriber accepted; ``lost`` counts records overwritten before
    it could read them.
    """

    __slots__ = (
        "_b",
        "count_word",
        "entry",
        "generation",
        "lost",
        "publisher_id",
        "record",
        "records",
        "region",
        "ring",
        "slot",
        "taken",
        "words",
    )

    def __init__(self, region: Region, slot: int, pub: int, publisher_id: int) -> None:
        self.region = region
        self.slot = slot
        self.publisher_id = publisher_id
        self.words = region.words
        self._b = region.bytes
        self.entry = region.pub_word(slot, pub, 0)
        self.count_word = region.counter_word(slot, C_PUBS + pub)
        self.taken = 0
        self.lost = 0
        self._load()

    def _load(self) -> None:
        w, e = self.words, self.entry
        self.generation = int(w[e + P_GENERATION])
        self.ring = int(w[e + P_RING])
        self.records = int(w[e + P_RECORDS])
        self.record = int(w[e + P_RECORD_BYTES])

    @property
    def count(self) -> int:
        return int(self.words[self.count_word])

    def header(self, n: int) -> RecordHeader | None:
        """The header of record ``n``, or None if it is not in the ring."""
        rec = self.ring + (n % self.records) * self.record
        q = rec >> 3
        w = self.words
        if w[q] != n:
            if w[self.entry + P_GENERATION] == self.generation:
                return None
            self._load()  # the ring was replaced: look in the new one
            rec = self.ring + (n % self.records) * self.record
            q = rec >> 3
            if w[q] != n:
                return None
        return RecordHeader(int(w[q + 1]), int(w[q + 2]), int(w[q + 3]), rec)

    def payload(self, rec: int) -> memoryview:
        size = int(self.words[(rec >> 3) + 4])
        return self._b[rec + RECORD_HEADER : rec + RECORD_HEADER + size]

    def still(self, n: int, rec: int) -> bool:
        """Record ``n`` was not overwritten while it was read."""
        return self.words[rec >> 3] == n

    def oldest_readable(self, count: int) -> int:
        """The first record after ``taken`` that can still be in the ring; skipped ones count as lost."""
        first = self.taken + 1
        floor = count - self.records + 1
        if first < floor:
            self.lost += floor - first
            self.taken = floor - 1
            return floor
        return first

    def take_new(self, horizon: int = 1 << 63) -> list[tuple[RecordHeader, bytes]]:
        """Every record not taken yet and published before ``horizon``, copied out with its header; records
        overwritten before they could be read count as lost."""
        count = self.count
        if count <= self.taken:
            return []
        taken: list[tuple[RecordHeader, bytes]] = []
        n = self.oldest_readable(count)
        w, b = self.words, self._b
        while n <= count:
            # header(), payload() and still() in line: a recorder reads every record of the run this way
            rec = self.ring + (n % self.records) * self.record
            q = rec >> 3
            if w[q] != n:
                head = self.header(n)  # the ring may have been replaced
                if head is None:
                    self.lost += 1
                    self.taken = n
                    n += 1
                    continue
                rec, q = head.offset, head.offset >> 3
            time_us = w[q + 2]
            if time_us >= horizon:
                break
            start = rec + RECORD_HEADER
            payload = bytes(b[start : start + w[q + 4]])
            head = RecordHeader(w[q + 1], time_us, w[q + 3], rec)
            if w[q] == n:
                taken.append((head, payload))
            else:
                self.lost += 1
            self.taken = n
            n += 1
        return taken


def next_trigger(readers: list[RingReader]) -> tuple[RingReader, int, RecordHeader] | None:
    """The earliest trigger record not taken yet, by (time, publisher id, sequence): its reader, number and header."""
    best: tuple[RingReader, int, RecordHeader] | None = None
    best_key = None
    for r in readers:
        count = r.words[r.count_word]
        n = r.taken + 1
        while n <= count:
            head = r.header(n)
            if head is not None:
                key = (head.time_us, r.publisher_id, head.seq)
                if best_key is None or key < best_key:
                    best, best_key = (r, n, head), key
                break
            r.lost += 1
            r.taken = n
            n += 1
    return best
