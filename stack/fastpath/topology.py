"""Who is in a fast-path run and what they publish, subscribe and are triggered by.

Every process rebuilds this from the region when the coordinator's topology counter changes (it does
so between steps when it admits or drops processes): publishers learn whom to wake and whether any
process reads a topic at all, subscribers which rings to read.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stack.fastpath.inputs import Source
from stack.fastpath.layout import (
    FLAG_READS_ALL,
    H_TOPOLOGY,
    ROLE_COORDINATOR,
    ROLE_PASSIVE,
    ROLE_TIMED,
    ROLE_TRIGGERED,
    S_EVENTFD,
    S_FLAGS,
    S_PERIOD,
    S_PUBLISHER_ID,
    S_ROLE,
    S_TRIGGER,
    Region,
)


@dataclass
class Participant:
    slot: int
    name: str
    role: int
    publisher_id: int
    eventfd: int
    trigger: int = 0
    period_us: int = 0
    flags: int = 0
    pubs: dict[int, int] = field(default_factory=dict)  # topic hash → publication index
    subs: dict[int, int] = field(default_factory=dict)  # topic hash → SUB_* flags

    @property
    def member(self) -> bool:
        return self.role in (ROLE_TIMED, ROLE_TRIGGERED)

    def reads(self, topic: int) -> bool:
        return topic in self.subs or bool(self.flags & FLAG_READS_ALL)


def participant(region: Region, slot: int) -> Participant:
    w = region.words
    p = Participant(
        slot=slot,
        name=region.slot_name(slot),
        role=int(w[region.slot_word(slot, S_ROLE)]),
        publisher_id=int(w[region.slot_word(slot, S_PUBLISHER_ID)]),
        eventfd=int(w[region.slot_word(slot, S_EVENTFD)]),
        trigger=int(w[region.slot_word(slot, S_TRIGGER)]),
        period_us=int(w[region.slot_word(slot, S_PERIOD)]),
        flags=int(w[region.slot_word(slot, S_FLAGS)]),
    )
    p.pubs = {pub.topic: pub.index for pub in region.publications(slot)}
    p.subs = dict(region.subscriptions(slot))
    return p


class Topology:
    """The admitted processes of the run, as the region says at ``generation``."""

    def __init__(self, region: Region) -> None:
        self.generation = int(region.words[H_TOPOLOGY])
        self.participants = [participant(region, s) for s in range(region.slots) if region.admitted(s)]
        self.publisher_ids = frozenset(p.publisher_id for p in self.participants)

    def sources(self, topic: int, exclude_slot: int = -1) -> list[Source]:
        """The rings ``topic`` is read from: a module reads its own publications as uORB's subscribers do,
        but is never triggered by them (``exclude_slot``)."""
        return [
            Source(p.slot, p.pubs[topic], p.publisher_id)
            for p in self.participants
            if topic in p.pubs and p.slot != exclude_slot
        ]

    def publishers_of(self, topic: int) -> frozenset[int]:
        """The publisher ids of the run's members that publish ``topic``."""
        return frozenset(p.publisher_id for p in self.participants if topic in p.pubs)

    def read_by_anyone(self, topic: int, publisher_slot: int) -> bool:
        return any(p.reads(topic) for p in self.participants if p.slot != publisher_slot)

    def woken_by(self, topic: int, publisher_slot: int) -> tuple[tuple[int, int], ...]:
        """(slot, eventfd) of the members a publication of ``topic`` triggers."""
        return tuple(
            (p.slot, p.eventfd)
            for p in self.participants
            if p.role == ROLE_TRIGGERED and p.trigger == topic and p.slot != publisher_slot
        )

    def coordinator(self) -> Participant | None:
        return next((p for p in self.participants if p.role == ROLE_COORDINATOR), None)

    def passive(self) -> list[Participant]:
        return [p for p in self.participants if p.role == ROLE_PASSIVE]
