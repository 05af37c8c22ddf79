"""The shared-memory region of a fast-path run: its layout, creation and per-slot views.

Everything is 64-bit words (native byte order). The region holds a header, one control block and
one counter block per module slot, and one heap per slot for that module's rings. Every word has a
single writer (named beside it), so no lock is ever needed: a reader that needs several counters
at once takes a snapshot and checks it did not change while it was taken (see
:meth:`Region.counter_snapshot`).
"""

from __future__ import annotations

import hashlib
import mmap
import os
from collections.abc import Iterator
from dataclasses import dataclass

MAGIC = 0x48544150_464B5453  # "STKFPATH"
VERSION = 1
MAX_SLOTS = 64
MAX_PUBS = 32
MAX_SUBS = 64
NAME_BYTES = 64

# Header words.
H_MAGIC = 0
H_VERSION = 1
H_NONCE = 2  # supervisor: the run's random id
H_SLOTS = 3  # supervisor
H_NOW = 4  # coordinator: simulated time of the current step (µs)
H_STEP = 5  # coordinator: steps taken
H_TOPOLOGY = 6  # coordinator: bumped whenever processes are admitted or dropped
H_ROSTER = 7  # supervisor: 1 once every module of the profile has been started
H_COORDINATOR = 8  # coordinator: its slot + 1 (0: none yet)
HEADER_WORDS = 64

# Control block words of a slot, with their writer.
S_EVENTFD = 0  # supervisor: the slot's eventfd (the same number in every process)
S_EXPECTED = 1  # supervisor: 1 if the module attaches to the fast path
S_RESTART = 2  # supervisor: 1 while a restart of the module is pending (lockstep time waits)
S_EXITS = 3  # supervisor: exits of the module handled so far
S_PID = 4  # module
S_INCARNATION = 5  # module: processes that attached to the slot so far
S_READY = 6  # module: the incarnation that finished attaching
S_ROLE = 7  # module: one of the ROLE_* values
S_TRIGGER = 8  # module: hash of its trigger topic (triggered members)
S_PERIOD = 9  # module: timer period in µs (timed members)
S_PUBLISHER_ID = 10  # module
S_NPUBS = 11  # module
S_NSUBS = 12  # module
S_HEAP_USED = 13  # module: bytes of the slot's heap allocated (kept across incarnations)
S_READ_TIME = 14  # module (lossless passive reader): every record older than this has been read
S_FLAGS = 15  # module: READS_ALL, LOSSLESS
S_ADMITTED = 16  # coordinator: the admitted incarnation (0: not admitted)
S_ADMIT_TIME = 17  # coordinator: the simulated time after which the admitted process's first step falls
S_AWAY = 18  # supervisor: 1 while the module's host is lost (lockstep time waits for it, without a stall verdict)
S_NAME = 24  # supervisor: the module name, NAME_BYTES of UTF-8
S_PUBS = S_NAME + NAME_BYTES // 8
PUB_WORDS = 16
S_SUBS = S_PUBS + MAX_PUBS * PUB_WORDS
S_BASE = S_SUBS + 2 * MAX_SUBS  # coordinator: per publisher slot, the count a triggered member starts after
SLOT_WORDS = 1024

# Words of a publication entry (in its module's control block).
P_TOPIC = 0  # topic hash
P_FINGERPRINT = 1  # schema fingerprint
P_RING = 2  # byte offset of the ring in the region
P_RECORDS = 3  # records in the ring
P_RECORD_BYTES = 4  # bytes per record (header included)
P_GENERATION = 5  # bumped when the ring is replaced by a larger one
P_ZENOH = 6  # supervisor: 1 while something outside the fast path subscribes to the topic
P_NAME = 8  # "topic/instance", NAME_BYTES of UTF-8

# Counter block words of a slot (contiguous over all slots, for snapshots).
C_STARTED = 0  # module: runs started
C_FINISHED = 1  # module: runs finished
C_TICKS = 2  # coordinator: timer ticks issued to the module
C_PUBS = 4  # module: records written per publication (by its index in the control block)
C_CONSUMED = C_PUBS + MAX_PUBS  # module: per publisher slot, index of the last trigger record taken
COUNTER_WORDS = 128

ROLE_NONE = 0
ROLE_COORDINATOR = 1
ROLE_TIMED = 2
ROLE_TRIGGERED = 3
ROLE_PASSIVE = 4

FLAG_READS_ALL = 1  # a passive reader of every topic (the recorder)
FLAG_LOSSLESS = 2  # lockstep time waits for this passive reader rather than let it lose records

SUB_TRIGGER = 1
SUB_QUEUE = 2

HEAP_BYTES = 64 << 20  # per slot; pages are only used once written


def topic_hash(suffix: str) -> int:
    """A topic's 64-bit id in the region, from its ``topic/instance`` suffix (never 0)."""
    return int.from_bytes(hashlib.blake2b(suffix.encode(), digest_size=8).digest(), "little") or 1


def region_size(slots: int) -> int:
    return 8 * (HEADER_WORDS + slots * (SLOT_WORDS + COUNTER_WORDS)) + slots * HEAP_BYTES


class Region:
    """A mapping of the run's shared-memory file. ``words`` is the whole region as unsigned 64-bit words."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        size = os.fstat(fd).st_size
        if size < 8 * HEADER_WORDS or size % 8:
            raise ValueError(f"fd {fd} is not a stack fast-path region ({size} bytes)")
        try:
            self.map = mmap.mmap(fd, size)
        except (OSError, ValueError) as e:
            raise ValueError(f"fd {fd} is not a stack fast-path region: {e}") from None
        self.bytes = memoryview(self.map)
        self.words = self.bytes.cast("Q")
        w = self.words
        if w[H_MAGIC] != MAGIC or w[H_VERSION] != VERSION:
            self.close()
            raise ValueError(f"fd {fd} is not a stack fast-path region of layout version {VERSION}")
        self.slots = int(w[H_SLOTS])
        if region_size(self.slots) != size:
            raise ValueError(f"fast-path region of {size} bytes does not match its {self.slots} slots")
        self.nonce = int(w[H_NONCE])
        self.counters_word = HEADER_WORDS + self.slots * SLOT_WORDS
        self.heap_offset = 8 * (self.counters_word + self.slots * COUNTER_WORDS)

    @staticmethod
    def create(names: list[str], nonce: int) -> Region:
        """A new region for modules ``names`` (slot i is names[i]); the caller owns and closes ``fd``."""
        if not 0 < len(names) <= MAX_SLOTS:
            raise ValueError(f"a fast-path run holds 1 to {MAX_SLOTS} modules, not {len(names)}")
        fd = os.memfd_create("stack-fastpath", os.MFD_CLOEXEC)
        os.ftruncate(fd, region_size(len(names)))
        with mmap.mmap(fd, 8 * HEADER_WORDS) as m:
            w = memoryview(m).cast("Q")
            w[H_MAGIC], w[H_VERSION], w[H_NONCE], w[H_SLOTS] = MAGIC, VERSION, nonce, len(names)
            w.release()
        region = Region(fd)
        for i, name in enumerate(names):
            region.write_text(region.slot_word(i, S_NAME), name)
        return region

    def close(self) -> None:
        self.words.release()
        self.bytes.release()
        self.map.close()

    # -- addressing ------------------------------------------------------------------------------

    def slot_word(self, slot: int, word: int) -> int:
        return HEADER_WORDS + slot * SLOT_WORDS + word

    def counter_word(self, slot: int, word: int) -> int:
        return self.counters_word + slot * COUNTER_WORDS + word

    def pub_word(self, slot: int, pub: int, word: int) -> int:
        return self.slot_word(slot, S_PUBS + pub * PUB_WORDS + word)

    def heap(self, slot: int) -> tuple[int, int]:
        """Byte offset and size of a slot's heap."""
        return self.heap_offset + slot * HEAP_BYTES, HEAP_BYTES

    def counter_snapshot(self) -> memoryview:
        """Every slot's counters at one instant: copied until two copies agree (the counters only grow)."""
        start, end = 8 * self.counters_word, 8 * (self.counters_word + self.slots * COUNTER_WORDS)
        raw = self.bytes[start:end]
        first = bytes(raw)
        while True:
            second = bytes(raw)
            if second == first:
                raw.release()
                return memoryview(second).cast("Q")
            first = second

    # -- text ------------------------------------------------------------------------------------

    def write_text(self, word: int, text: str) -> None:
        data = text.encode()
        if len(data) > NAME_BYTES:
            raise ValueError(f"'{text}' is longer than {NAME_BYTES} bytes")
        self.bytes[8 * word : 8 * word + NAME_BYTES] = data.ljust(NAME_BYTES, b"\0")

    def read_text(self, word: int) -> str:
        return bytes(self.bytes[8 * word : 8 * word + NAME_BYTES]).rstrip(b"\0").decode(errors="replace")

    def slot_name(self, slot: int) -> str:
        return self.read_text(self.slot_word(slot, S_NAME))

    def slot_of(self, name: str) -> int:
        for i in range(self.slots):
            if self.slot_name(i) == name:
                return i
        raise ValueError(f"no fast-path slot for module '{name}'")

    # -- directory -------------------------------------------------------------------------------

    def publications(self, slot: int) -> Iterator[Publication]:
        w = self.words
        for j in range(int(w[self.slot_word(slot, S_NPUBS)])):
            yield Publication(
                slot=slot,
                index=j,
                topic=int(w[self.pub_word(slot, j, P_TOPIC)]),
                name=self.read_text(self.pub_word(slot, j, P_NAME)),
                fingerprint=int(w[self.pub_word(slot, j, P_FINGERPRINT)]),
            )

    def subscriptions(self, slot: int) -> Iterator[tuple[int, int]]:
        """(topic hash, SUB_* flags) of a slot's subscriptions."""
        w = self.words
        for k in range(int(w[self.slot_word(slot, S_NSUBS)])):
            base = self.slot_word(slot, S_SUBS + 2 * k)
            yield int(w[base]), int(w[base + 1])

    def attached(self, slot: int) -> bool:
        """The slot's current process has finished attaching (and has not been replaced since)."""
        w = self.words
        incarnation = w[self.slot_word(slot, S_INCARNATION)]
        return incarnation > 0 and w[self.slot_word(slot, S_READY)] == incarnation

    def admitted(self, slot: int) -> bool:
        w = self.words
        admitted = w[self.slot_word(slot, S_ADMITTED)]
        return admitted > 0 and admitted == w[self.slot_word(slot, S_INCARNATION)]


@dataclass(frozen=True)
class Publication:
    slot: int
    index: int
    topic: int
    name: str
    fingerprint: int
