"""When lockstep time may advance: the step's accounting, written once for every transport.

Each participant of a lockstep run keeps cumulative counters that only it writes: runs started and
finished, and, per publisher of its trigger topic, the index of the last trigger message it took. Each
publisher counts the messages it wrote per topic; the coordinator counts the timer ticks it issued to
each timed member. A step is over when every member is idle with nothing left to take:

- a timed member has started and finished every tick issued to it;
- a triggered member has started and finished every run, and has taken every message each publisher of
  its trigger wrote after the member's *base* for it (that publisher's count when either of them was
  admitted: a member admitted late, or restarted, never waits for a message written before it came).

How the counters travel is the transport's business: on one host they are words of the shared region
(:mod:`stack.fastpath.layout`), read in one consistent snapshot; over Zenoh the coordinator keeps them from
the members' acknowledgements. Either way the ledger reads them from a sequence of integers, by the
indices a :class:`TimedMember` or :class:`TriggeredMember` names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class TriggerSource:
    """One publisher of a triggered member's trigger topic, as counter indices and the member's base."""

    published: int
    """Index of the publisher's count of messages written on the topic."""
    taken: int
    """Index of the member's index of the last message of this publisher it took."""
    base: int
    """The publisher's count when the member (or the publisher) was admitted: earlier messages are not awaited."""


@dataclass(frozen=True, slots=True)
class TimedMember:
    name: str
    key: int
    """How the transport knows the member (its slot on the fast path)."""
    started: int
    finished: int
    ticks: int


@dataclass(frozen=True, slots=True)
class TriggeredMember:
    name: str
    key: int
    started: int
    finished: int
    sources: tuple[TriggerSource, ...]


class StepLedger:
    """The members of the run as counter indices; :meth:`complete` tells whether the step is over."""

    __slots__ = ("timed", "triggered")

    def __init__(self, timed: Sequence[TimedMember] = (), triggered: Sequence[TriggeredMember] = ()) -> None:
        self.timed = tuple(timed)
        self.triggered = tuple(triggered)

    def complete(self, counters: Sequence[int]) -> bool:
        """Whether every member is idle with nothing left to take (``counters``: one consistent snapshot)."""
        for m in self.timed:
            started = counters[m.started]
            if started != counters[m.finished] or started != counters[m.ticks]:
                return False
        for t in self.triggered:
            if counters[t.started] != counters[t.finished]:
                return False
            for s in t.sources:
                published = counters[s.published]
                if published > s.base and published > counters[s.taken]:
                    return False
        return True

    def with_work(self, counters: Sequence[int]) -> list[tuple[TimedMember | TriggeredMember, bool]]:
        """The members that are not done: each with whether it is in the middle of a run (else it has work
        waiting that it has not started, and a lost wake-up may be why)."""
        found: list[tuple[TimedMember | TriggeredMember, bool]] = []
        for m in self.timed:
            running = counters[m.started] != counters[m.finished]
            if running or counters[m.ticks] != counters[m.started]:
                found.append((m, running))
        for t in self.triggered:
            running = counters[t.started] != counters[t.finished]
            waiting = any(
                counters[s.published] > s.base and counters[s.published] > counters[s.taken] for s in t.sources
            )
            if running or waiting:
                found.append((t, running))
        return found
