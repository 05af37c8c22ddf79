"""A module process's place in a fast-path run: its slot, publications and subscriptions.

The supervisor passes the region's file descriptor and names the slot; the process fills the slot
(its publications keep the rings of an earlier process of the same slot, so a restarted module
continues its topics' counts), says which role it takes, and marks itself ready. From then on the
coordinator may admit it, between two steps.
"""

from __future__ import annotations

import os

from stack.fastpath.layout import (
    C_FINISHED,
    C_STARTED,
    MAX_SUBS,
    S_EVENTFD,
    S_FLAGS,
    S_INCARNATION,
    S_NSUBS,
    S_PERIOD,
    S_PID,
    S_PUBLISHER_ID,
    S_READY,
    S_ROLE,
    S_SUBS,
    S_TRIGGER,
    Region,
    topic_hash,
)
from stack.fastpath.ring import RingWriter, declare_publication


class Attachment:
    """This process in the run (one per process). Call :meth:`ready` once its topics are declared."""

    def __init__(self, region: Region, name: str, publisher_id: int) -> None:
        self.region = region
        self.slot = slot = region.slot_of(name)
        w, sw = region.words, region.slot_word
        self.incarnation = int(w[sw(slot, S_INCARNATION)]) + 1
        w[sw(slot, S_INCARNATION)] = self.incarnation
        w[sw(slot, S_PID)] = os.getpid()
        w[sw(slot, S_PUBLISHER_ID)] = publisher_id
        w[sw(slot, S_NSUBS)] = 0
        w[sw(slot, S_ROLE)] = 0
        w[sw(slot, S_FLAGS)] = 0
        started, finished = region.counter_word(slot, C_STARTED), region.counter_word(slot, C_FINISHED)
        w[finished] = w[started]  # a run the previous process of this slot died in is abandoned
        self.eventfd = int(w[sw(slot, S_EVENTFD)])
        self.wakes: set[int] = set()  # eventfds this process's records trigger, woken after each run

    def publication(self, suffix: str, fingerprint: int, sample_payload: int) -> RingWriter:
        pub = declare_publication(self.region, self.slot, suffix, fingerprint, sample_payload)
        return RingWriter(self.region, self.slot, pub, self.wakes)

    def subscription(self, suffix: str, flags: int) -> None:
        w, sw = self.region.words, self.region.slot_word
        n = int(w[sw(self.slot, S_NSUBS)])
        if n >= MAX_SUBS:
            raise ValueError(f"a module may subscribe to at most {MAX_SUBS} topics on the fast path")
        w[sw(self.slot, S_SUBS + 2 * n)] = topic_hash(suffix)
        w[sw(self.slot, S_SUBS + 2 * n + 1)] = flags
        w[sw(self.slot, S_NSUBS)] = n + 1

    def ready(self, role: int, *, trigger: str = "", period_us: int = 0, flags: int = 0) -> None:
        w, sw = self.region.words, self.region.slot_word
        w[sw(self.slot, S_ROLE)] = role
        w[sw(self.slot, S_TRIGGER)] = topic_hash(trigger) if trigger else 0
        w[sw(self.slot, S_PERIOD)] = period_us
        w[sw(self.slot, S_FLAGS)] = flags
        w[sw(self.slot, S_READY)] = self.incarnation
