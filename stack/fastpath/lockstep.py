"""Lockstep over the fast path: the coordinator (the simulator) and the members.

A step at time ``t``: between steps the coordinator admits processes that have attached and drops
those that died; it writes ``t``, ticks the timed members that are due, and runs its own module,
whose publications wake the members they trigger, whose publications wake others in turn. A member
runs once per tick or trigger record. When it has no work left it wakes the coordinator, unless a
member it woke itself is still busy (that one will). The coordinator ends the step when a snapshot of
the counters shows every admitted member idle with nothing left to take.

Nothing here depends on a message arriving in time: the coordinator's waits time out every few
milliseconds and then wake again any member with work left (a lost wake-up costs milliseconds, never
the run). A member that dies is noticed through its pidfd at once and dropped; if the supervisor
restarts it, time waits until the new process is admitted. A member that makes no progress for
``stall_timeout_s`` is named and the run stops; while the supervisor says a member's host is lost, time
waits for it without that verdict, which counts again from the host's return.
"""

from __future__ import annotations

import logging
import os
import select
import time
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from stack.fastpath.attach import Attachment
from stack.fastpath.layout import (
    C_CONSUMED,
    C_FINISHED,
    C_PUBS,
    C_STARTED,
    C_TICKS,
    FLAG_LOSSLESS,
    H_COORDINATOR,
    H_NOW,
    H_ROSTER,
    H_STEP,
    H_TOPOLOGY,
    ROLE_TIMED,
    ROLE_TRIGGERED,
    S_ADMIT_TIME,
    S_ADMITTED,
    S_AWAY,
    S_BASE,
    S_EXITS,
    S_EXPECTED,
    S_INCARNATION,
    S_PID,
    S_READ_TIME,
    S_RESTART,
)
from stack.fastpath.ring import RingWriter
from stack.fastpath.topology import Participant, Topology
from stack.runtime.ledger import (
    SLOW_WAIT_S,
    Departure,
    Departures,
    LockstepError,
    StallWatch,
    StepLedger,
    TimedMember,
    TriggeredMember,
    TriggerSource,
    Word,
    timer_due,
)
from stack.runtime.start_deadline import StartDeadline

log = logging.getLogger("stack.lockstep")

WAIT_MS = 5
LAG_WAKE_STEPS = 32
ADMIT_SCAN_STEPS = 250
LAG_MAX_STEPS = 128


def drain(fd: int) -> None:
    """Reset an eventfd that poll() found readable (only its owner reads it, so this never blocks)."""
    os.eventfd_read(fd)


class Beside(Protocol):
    """Members sharing the coordinator's process (stack.runtime.fastrun.ProcessGroup)."""

    eventfds: list[int]

    def mark(self, fd: int) -> None:
        """Give the member of eventfd ``fd`` work without a system call (it runs at the next pump)."""

    def pump(self, woken: Iterable[int] = ()) -> None:
        """Run the members woken (their eventfds ``woken`` and those marked) until none is left."""


@dataclass
class _Watched:
    name: str
    pid: int
    incarnation: int
    pidfd: int
    exits: int  # the supervisor's count of this module's exits when it was admitted


class FastCoordinator:
    """The clock's side. Call :meth:`start` once, then :meth:`begin_step` and :meth:`finish_step` per step."""

    def __init__(
        self,
        att: Attachment,
        period_us: int,
        stall_timeout_s: float,
        beside: Beside | None = None,
    ) -> None:
        """``beside``: the members sharing the coordinator's process, run while it waits."""
        self.att = att
        self.region = region = att.region
        self.w = region.words
        self.period_us = period_us
        self._stall = StallWatch(stall_timeout_s)
        self.now = 0
        self.steps = 0
        self._poll = select.poll()
        self._poll.register(att.eventfd, select.POLLIN)
        self._beside = beside
        self._pump_fds = frozenset(beside.eventfds if beside is not None else ())
        for fd in self._pump_fds:
            self._poll.register(fd, select.POLLIN)
        self._watched: dict[int, _Watched] = {}
        self._pidfd_slot: dict[int, int] = {}
        self._departures = Departures()
        self._gone: dict[int, int] = {}  # slot → the last incarnation seen to die (never admitted again)
        self._last_fire: dict[int, int | None] = {}
        self._topology = Topology(region)
        # The step's accounting, with counter indices relative to the counter block (as in a snapshot).
        self._ledger = StepLedger()
        self._members: dict[int, Participant] = {}  # slot → member
        self._passive: list[Participant] = []
        self._lag_woken: dict[int, int] = {}
        self.w[H_COORDINATOR] = att.slot + 1

    # -- start -------------------------------------------------------------------------------------

    def start(self) -> None:
        """Block until the supervisor has started every module and each has attached, then admit them."""
        region, w = self.region, self.w
        deadline = StartDeadline()
        while True:
            missing = [
                region.slot_name(s)
                for s in range(region.slots)
                if s != self.att.slot and w[region.slot_word(s, S_EXPECTED)] and not region.attached(s)
            ]
            if w[H_ROSTER] and not missing:
                break
            if deadline.passed(bool(w[H_ROSTER])):
                raise LockstepError(f"lockstep start timed out waiting for {', '.join(missing)}")
            self._reap(10)
        w[region.slot_word(self.att.slot, S_ADMITTED)] = self.att.incarnation
        self._admit_attached()
        names = sorted(p.name for p in self._topology.participants)
        log.info("lockstep starting with %s (shared-memory fast path)", ", ".join(names))

    # -- between steps -----------------------------------------------------------------------------

    def begin_step(self) -> int:
        """Settle membership, then announce the next step's time and tick the due timed members."""
        self._settle()
        t = self.now + self.period_us
        self.now = t
        self.steps += 1
        w = self.w
        w[H_NOW] = t
        w[H_STEP] = self.steps
        last_fire = self._last_fire
        counters = self.region.counters_word
        members, local, beside = self._members, self._pump_fds, self._beside
        for timed in self._ledger.timed:
            m = members[timed.key]
            if timer_due(t, last_fire[m.slot], m.period_us):
                last_fire[m.slot] = t
                w[counters + timed.ticks] += 1
                if beside is not None and m.eventfd in local:
                    beside.mark(m.eventfd)
                else:
                    os.eventfd_write(m.eventfd, 1)
        return t

    def _settle(self) -> None:
        """Admit who attached; wait for restarts the supervisor announced and for lossless readers to catch up.

        A passive reader that falls LAG_WAKE_STEPS behind is woken to read (before its rings wrap); time
        waits only for a lossless one (the recorder), and only once it is LAG_MAX_STEPS behind.

        Processes attach at start (all admitted then) or after a restart (announced by a death), so the
        slots are scanned for newcomers only while a restart is awaited, and every ADMIT_SCAN_STEPS steps.
        """
        scan = bool(self._departures) or self.steps % ADMIT_SCAN_STEPS == 0
        if not (scan or self._passive):
            return
        started_waiting = 0.0
        while True:
            if scan:
                self._admit_attached()
            waiting = self._waiting_for()
            if not waiting:
                return
            if not started_waiting:
                started_waiting = time.monotonic()
            elif started_waiting > 0 and time.monotonic() - started_waiting > SLOW_WAIT_S:
                started_waiting = -1.0
                log.warning("lockstep time waits at t=%.3f s for %s", self.now / 1e6, ", ".join(waiting))
            self._reap(WAIT_MS)

    def _waiting_for(self) -> list[str]:
        region, w = self.region, self.w
        waiting = self._departures.awaited(self._word, time.monotonic())
        for name in self._departures.silent:
            log.warning("no word from the supervisor on %s: time goes on", name)
        lag_wake, lag_max = LAG_WAKE_STEPS * self.period_us, LAG_MAX_STEPS * self.period_us
        for p in self._passive:
            lag = self.now - int(w[region.slot_word(p.slot, S_READ_TIME)])
            if lag >= lag_wake and self._lag_woken.get(p.slot) != self.steps:
                self._lag_woken[p.slot] = self.steps
                os.eventfd_write(p.eventfd, 1)
            if lag >= lag_max and p.flags & FLAG_LOSSLESS:
                waiting.append(f"{p.name} to catch up")
        return waiting

    def _word(self, departure: Departure) -> Word:
        """The supervisor's word on a member that left, from its slot: a higher count of exits, and whether a
        restart is pending."""
        slot = self.region.slot_of(departure.name)
        if self.w[self.region.slot_word(slot, S_EXITS)] <= departure.exits:
            return Word.NONE
        return Word.RESTARTING if self.w[self.region.slot_word(slot, S_RESTART)] else Word.GONE

    def _admit_attached(self) -> None:
        region, w = self.region, self.w
        admitted = []
        for slot in range(region.slots):
            if slot == self.att.slot:
                continue
            watched = self._watched.get(slot)
            incarnation = int(w[region.slot_word(slot, S_INCARNATION)])
            if watched is not None and watched.incarnation != incarnation:
                self._drop(slot, "was replaced")
            if slot in self._watched or not region.attached(slot) or self._gone.get(slot) == incarnation:
                continue
            pid = int(w[region.slot_word(slot, S_PID)])
            try:
                pidfd = os.pidfd_open(pid)
            except ProcessLookupError:
                continue
            name = region.slot_name(slot)
            self._watched[slot] = _Watched(name, pid, incarnation, pidfd, int(w[region.slot_word(slot, S_EXITS)]))
            self._pidfd_slot[pidfd] = slot
            self._poll.register(pidfd, select.POLLIN)
            self._departures.back(name)
            w[region.slot_word(slot, S_ADMIT_TIME)] = self.now + 1
            w[region.slot_word(slot, S_ADMITTED)] = incarnation
            admitted.append(slot)
            if self.steps:
                log.info("lockstep: %s admitted at t=%.3f s", name, self.now / 1e6)
        if admitted:
            self._rebuild(set(admitted))

    def _drop(self, slot: int, why: str) -> None:
        watched = self._watched.pop(slot)
        self._gone[slot] = watched.incarnation
        self._poll.unregister(watched.pidfd)
        del self._pidfd_slot[watched.pidfd]
        os.close(watched.pidfd)
        self.w[self.region.slot_word(slot, S_ADMITTED)] = 0
        self._departures.left(watched.name, time.monotonic(), watched.exits)
        # Information, not a warning: the supervisor says whether the process failed (a scenario that
        # finished its flight ends as planned).
        log.info("lockstep member %s %s at t=%.3f s", watched.name, why, self.now / 1e6)
        self._rebuild(set())

    def _rebuild(self, new: set[int]) -> None:
        """New topology: ticks and trigger bases for the newly admitted, the completion checks for all."""
        region, w = self.region, self.w
        w[H_TOPOLOGY] = w[H_TOPOLOGY] + 1
        topo = self._topology = Topology(region)
        publishers = {p.slot: p for p in topo.participants}
        me = self.att.slot
        first = region.counters_word
        timed, triggered = [], []
        for m in topo.participants:
            started = region.counter_word(m.slot, C_STARTED) - first
            finished = region.counter_word(m.slot, C_FINISHED) - first
            if m.role == ROLE_TIMED:
                ticks = region.counter_word(m.slot, C_TICKS)
                if m.slot in new:
                    w[ticks] = w[started + first]
                    self._last_fire[m.slot] = None
                timed.append(TimedMember(m.name, m.slot, started, finished, ticks - first))
            elif m.role == ROLE_TRIGGERED:
                sources = []
                for p in publishers.values():
                    if p.slot == m.slot or m.trigger not in p.pubs:
                        continue
                    count = region.counter_word(p.slot, C_PUBS + p.pubs[m.trigger])
                    base = region.slot_word(m.slot, S_BASE + p.slot)
                    if m.slot in new or p.slot in new:
                        w[base] = w[count]
                    taken = region.counter_word(m.slot, C_CONSUMED + p.slot)
                    sources.append(TriggerSource(count - first, taken - first, int(w[base])))
                triggered.append(TriggeredMember(m.name, m.slot, started, finished, tuple(sources)))
        self._ledger = StepLedger(timed, triggered)
        self._members = {m.slot: m for m in topo.participants if m.member}
        self._passive = [p for p in topo.passive() if p.slot != me]

    # -- the step ----------------------------------------------------------------------------------

    def finish_step(self) -> None:
        """Block until every run of the step has finished (see the module docstring)."""
        stall = self._stall
        stall.start(time.monotonic())
        while True:
            snap = self.region.counter_snapshot()
            if self._ledger.complete(snap):
                return
            if self._reap(WAIT_MS):
                continue
            if self._away():
                stall.start(time.monotonic())  # time waits for a lost host; the verdict counts from its return
            stall.check(snap.obj, time.monotonic(), self.now, lambda snap=snap: self._busy(snap))
            self._rewake(snap)

    def _away(self) -> bool:
        """Whether the supervisor says the host of a member is lost."""
        return any(self.w[self.region.slot_word(slot, S_AWAY)] for slot in self._members)

    def _rewake(self, snap: memoryview) -> None:
        """A member with work and no run going may have missed its wake-up: wake it again (harmless if not)."""
        for m, running in self._ledger.with_work(snap):
            if not running:
                os.eventfd_write(self._members[m.key].eventfd, 1)

    def _busy(self, snap: memoryview) -> list[str]:
        names = {}
        for p in self._topology.participants:
            for pub in self.region.publications(p.slot):
                names[pub.topic] = pub.name
        members = self._members
        described = []
        for entry, _ in self._ledger.with_work(snap):
            m = members[entry.key]
            described.append(f"{m.name} ({names.get(m.trigger, '?') if m.role == ROLE_TRIGGERED else '@timer'})")
        return described

    def _reap(self, timeout_ms: int) -> bool:
        """Wait up to ``timeout_ms`` for a wake-up or a death, dropping members that died; False on timeout."""
        events = self._poll.poll(timeout_ms)
        woken = []
        for fd, _ in events:
            if fd == self.att.eventfd:
                drain(fd)
            elif fd in self._pump_fds:
                drain(fd)
                woken.append(fd)
            elif (slot := self._pidfd_slot.get(fd)) is not None:
                self._drop(slot, "left")
        if woken and self._beside is not None:
            self._beside.pump(woken)
        return bool(events)

    def close(self) -> None:
        for watched in self._watched.values():
            os.close(watched.pidfd)
        self._watched.clear()


class FastMember:
    """A member's side: sleep until woken, and after a batch of runs wake the coordinator if the step may be over.

    It may be over when the members this batch woke have taken what it published and are idle, and no
    other member is running or has a tick it has not started: then this member may be the last one
    at work. Otherwise whichever member finishes last will say so (each wake costs the coordinator a
    context switch, so a step is announced over once, not once per member).
    """

    def __init__(self, att: Attachment) -> None:
        self.att = att
        self.region = region = att.region
        self.w = region.words
        self._poll = select.poll()
        self._poll.register(att.eventfd, select.POLLIN)
        me = att.slot
        self.started = region.counter_word(me, C_STARTED)
        self.finished = region.counter_word(me, C_FINISHED)
        self.ticks = region.counter_word(me, C_TICKS)
        self._admitted_word = region.slot_word(me, S_ADMITTED)
        self._incarnation_word = region.slot_word(me, S_INCARNATION)
        self.topology_seen = -1
        self.coordinator_fd = -1
        self._others: list[tuple[int, int, int]] = []  # (started, finished, ticks) words of the other members

    def wait(self) -> None:
        self._poll.poll()
        os.eventfd_read(self.att.eventfd)

    def admitted(self) -> bool:
        w = self.w
        admitted = w[self._admitted_word]
        return admitted != 0 and admitted == w[self._incarnation_word]

    def on_topology(self, topo: Topology) -> None:
        self.topology_seen = topo.generation
        c = topo.coordinator()
        self.coordinator_fd = c.eventfd if c is not None else -1
        cw = self.region.counter_word
        self._others = [
            (cw(p.slot, C_STARTED), cw(p.slot, C_FINISHED), cw(p.slot, C_TICKS))
            for p in topo.participants
            if p.member and p.slot != self.att.slot
        ]

    def base(self, publisher_slot: int) -> int:
        return int(self.w[self.region.slot_word(self.att.slot, S_BASE + publisher_slot)])

    def consumed_word(self, publisher_slot: int) -> int:
        return self.region.counter_word(self.att.slot, C_CONSUMED + publisher_slot)

    def done(self, touched: list[RingWriter]) -> None:
        """After a batch of runs: wake the coordinator unless a member this batch woke is still at work."""
        w, region, me = self.w, self.region, self.att.slot
        for writer in touched:
            count = w[writer.count_word]
            for slot, _ in writer.wake:
                consumed = w[region.counter_word(slot, C_CONSUMED + me)]
                if consumed < count and w[region.slot_word(slot, S_BASE + me)] < count:
                    return
                if w[region.counter_word(slot, C_STARTED)] != w[region.counter_word(slot, C_FINISHED)]:
                    return
        for started, finished, ticks in self._others:
            s = w[started]
            if s != w[finished] or w[ticks] > s:
                return
        if self.coordinator_fd >= 0:
            os.eventfd_write(self.coordinator_fd, 1)
