"""When lockstep time may advance: the step's accounting and the members that left, written once for every
transport.

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

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass

SLOW_WAIT_S = 2.0
"""A wait of the lockstep longer than this is said in the log (once per wait)."""
VERDICT_TIMEOUT_S = 5.0
"""How long time waits for the supervisor's word on a member that left before it goes on without it."""


class LockstepError(RuntimeError):
    """The lockstep cannot continue (a member stalled past the timeout)."""


def timer_due(t: int, last_fire: int | None, period_us: int) -> bool:
    """Whether a timer of ``period_us`` that last fired at ``last_fire`` fires at step ``t``: on the first step of
    each period-aligned interval (the coordinator ticks by this rule, whatever the transport)."""
    return last_fire is None or t // period_us > last_fire // period_us


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


class StallWatch:
    """The verdict on a step that does not end: it makes progress while its counters change, and none for
    ``timeout_s`` is a stall, which stops the run naming who has work left (PX4 SITL's lockstep would hang)."""

    __slots__ = ("_last", "_since", "timeout_s")

    def __init__(self, timeout_s: float) -> None:
        self.timeout_s = timeout_s
        self._last: object = None
        self._since = 0.0

    def start(self, now_s: float) -> None:
        """A step's wait begins."""
        self._last, self._since = None, now_s

    def check(self, counters: object, now_s: float, now_us: int, waiting: Callable[[], list[str]]) -> None:
        """Note the counters as seen now (any comparable value); raise LockstepError, naming ``waiting()``, once
        they have not changed for the timeout."""
        if counters != self._last:
            self._last, self._since = counters, now_s
        elif now_s - self._since > self.timeout_s:
            raise LockstepError(
                f"lockstep stalled at t={now_us / 1e6:.3f} s: no progress for {self.timeout_s:.0f} s, "
                f"waiting for {', '.join(sorted(waiting()))}"
            )


class Word(enum.Enum):
    """What the supervisor says of a member that left the run."""

    GONE = "gone"
    """It will not be back (it exited or failed, and no restart is coming): time goes on without it."""
    RESTARTING = "restarting"
    """A new process is on its way: time waits until it is admitted."""
    NONE = "none"
    """No word yet: time waits for one, at most VERDICT_TIMEOUT_S."""


@dataclass(slots=True)
class Departure:
    name: str
    since_s: float
    """When it left (monotonic seconds)."""
    exits: int = 0
    """The supervisor's count of the module's exits when it was admitted (its word is a higher count)."""


class Departures:
    """Members that left the run, until the supervisor's word on each (PX4 SITL has one process and no such
    question): time waits while one is being restarted, and goes on without one that is gone or of which no
    word comes within VERDICT_TIMEOUT_S."""

    __slots__ = ("_left", "silent")

    def __init__(self) -> None:
        self._left: dict[str, Departure] = {}
        self.silent: list[str] = []
        """Members given up for want of a word, since the last :meth:`awaited` (for the caller to log)."""

    def __bool__(self) -> bool:
        return bool(self._left)

    def left(self, name: str, now_s: float, exits: int = 0) -> None:
        self._left[name] = Departure(name, now_s, exits)

    def back(self, name: str) -> None:
        self._left.pop(name, None)

    def awaited(self, word: Callable[[Departure], Word], now_s: float) -> list[str]:
        """What time still waits for, given the supervisor's ``word`` on each departure."""
        waiting = []
        self.silent = []
        for name, departure in list(self._left.items()):
            said = word(departure)
            if said is Word.GONE:
                del self._left[name]
            elif said is Word.RESTARTING:
                waiting.append(f"{name} to restart")
            elif now_s - departure.since_s > VERDICT_TIMEOUT_S:
                del self._left[name]
                self.silent.append(name)
            else:
                waiting.append(f"the supervisor's word on {name}")
        return waiting
