"""Lockstep over Zenoh: simulated time advances only when every module triggered by the last step is done.

This is PX4 SITL's lockstep spread over processes. One module, the simulator, drives it as the
*coordinator*; every other triggered or timed module is a *member*. A run whose modules are all
started by one supervisor on one host uses the shared-memory fast path instead (:mod:`stack.fastpath`,
the same rules with other means); this transport serves profiles that choose
``lockstep_transport = "zenoh"``, e.g. for members on several hosts.

- Each member declares a liveliness token naming its trigger topic or its timer period.
- The coordinator publishes a clock message per step (the new time, the members expected to act,
  and the cumulative publication counts up to the previous step), then its own messages. Timed
  members receive the clock on their own key, and only on the steps their timer is due, so a 50 Hz
  module is not woken 250 times a second.
- A member runs once per trigger message (or per tick) and then acknowledges, reporting its message
  totals per topic and which trigger message (publisher and index) it took.
- From the acknowledgements the coordinator keeps every participant's counters, and the step is done
  when :class:`stack.runtime.ledger.StepLedger` says so (every tick run, every trigger message taken);
  only then does time advance.
- Before acting at time ``t`` a member waits until it holds every message the counts say was
  published before ``t`` (the *barrier*). With the visibility rules of :mod:`stack.runtime.inputs`
  this makes every run see the same inputs whatever the process scheduling, so lockstep runs with
  the same seed are identical.

A member that dies is dropped (and named) at once; if the supervisor restarts it, time waits until
it is back, and it joins at the current step, waiting only for messages published after it joined.
One that stalls is named after a timeout and the coordinator stops with an error rather than hang
silently. The protocol's own messages carry the run's id: a message that does not decode, or comes
from another run, is counted and ignored, so nothing sent on the bus can stop the run.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Generic, TypeVar

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.node import Node
from stack.bus.supervisors import module_states
from stack.bus.topics import TopicPublisher
from stack.msg.internal import LockstepAck, LockstepClock
from stack.runtime.inputs import InputBuffer
from stack.runtime.ledger import (
    SLOW_WAIT_S,
    Departures,
    StallWatch,
    StepLedger,
    TimedMember,
    TriggeredMember,
    TriggerSource,
    Word,
    timer_due,
)

log = logging.getLogger("stack.lockstep")

TIMER = "@timer"
# A timed member's ticks wait in a FIFO it drains on every tick. A triggered member's clocks are decoded as they
# arrive and only valid ones are queued, the oldest dropped beyond CLOCK_QUEUE: garbage on the key never pushes a
# clock out, and a member that is not triggered for minutes (the allocator of a disarmed vehicle) never fills a
# queue that would block the session's receiving thread and, through it, the coordinator's clock.
CLOCK_QUEUE = 1 << 11  # 8 s of the SIH quad's 4 ms steps
_WAKE = "@wake"
_encoder = msgspec.msgpack.Encoder()

P = TypeVar("P", LockstepClock, LockstepAck)


class ProtocolDecoder(Generic[P]):
    """Decodes the lockstep's own messages; what does not decode or belongs to another run is counted and dropped."""

    def __init__(self, kind: type[P], run_id: int, where: str) -> None:
        self._decoder = msgspec.msgpack.Decoder(kind)
        self._run_id = run_id
        self._where = where
        self.rejected = 0

    def decode(self, sample: zenoh.Sample) -> P | None:
        try:
            msg = self._decoder.decode(sample.payload.to_bytes())
        except msgspec.DecodeError:
            msg = None
        if msg is not None and msg.run == self._run_id:
            return msg
        self.rejected += 1
        if self.rejected == 1 or self.rejected % 1000 == 0:
            why = "does not decode" if msg is None else "is from outside this run"
            log.warning("%s: ignored a message that %s (%d so far)", self._where, why, self.rejected)
        return None


class Barrier:
    """Waits until each subscription holds the newest message the lockstep counts announce."""

    def __init__(self, inputs: Iterable[InputBuffer]) -> None:
        self.by_suffix = {buf.sub.suffix: buf for buf in inputs}
        self.required: dict[tuple[int, str], int] = {}

    def require(self, publisher_id: int, suffix: str, total: int) -> None:
        if suffix in self.by_suffix:
            self.required[(publisher_id, suffix)] = total

    def wait(self) -> None:
        if not self.required:
            return
        spins = 0
        started = 0.0
        while not self._satisfied():
            spins += 1
            if spins < 100:
                time.sleep(0)
                continue
            time.sleep(0.0002)
            if not started:
                started = time.monotonic()
            elif started > 0.0 and time.monotonic() - started > SLOW_WAIT_S:
                started = -1.0  # report once per wait
                log.warning("lockstep barrier: still waiting after %.0f s for %s", SLOW_WAIT_S, self.describe())

    def describe(self) -> str:
        """The messages the barrier still waits for (topic, publisher, index wanted and held)."""
        return ", ".join(
            f"{suffix} #{total} from publisher {pub} (holding #{self.by_suffix[suffix].last_index.get(pub, 0)})"
            for (pub, suffix), total in self.required.items()
        )

    def _satisfied(self) -> bool:
        for key, total in list(self.required.items()):
            pub, suffix = key
            buf = self.by_suffix[suffix]
            if buf.last_index.get(pub, 0) < total:
                buf.pull()
                if buf.last_index.get(pub, 0) < total:
                    return False
            del self.required[key]
        return True


class LockstepMember:
    """The member side: follows the clock, holds the barrier, acknowledges runs.

    A timed member blocks on its own tick key (``next_clock``). A triggered member blocks on its
    trigger topic; its clock subscription is read when a trigger arrives (``advance_to``; the counts in
    each clock are cumulative, so only the newest matters). Neither is woken by clocks it does not need.
    The first clock that admits the member sets its floor: it never waits for a message published
    before it joined (a restarted member would wait forever for those).
    """

    def __init__(self, node: Node, inputs: Iterable[InputBuffer], trigger: str, timed: bool) -> None:
        self.node = node
        self.trigger = trigger
        self.timed = timed
        self.now = 0
        self.step = 0
        self.admitted = False
        self.registered = False
        self.heard_coordinator = False
        self.members: frozenset[int] = frozenset()
        self.barrier = Barrier(inputs)
        self._floor: dict[tuple[int, str], int] | None = None
        key = keys.lockstep_tick_key(node.vehicle, node.name) if timed else keys.lockstep_clock_key(node.vehicle)
        self._clocks = ProtocolDecoder(LockstepClock, node.run_id, key)
        self._arrived: collections.deque[LockstepClock] = collections.deque(maxlen=CLOCK_QUEUE)
        if timed:
            self._clock_sub = node.session.declare_subscriber(key, zenoh.handlers.FifoChannel(CLOCK_QUEUE))
        else:
            self._clock_sub = node.session.declare_subscriber(key, self._on_clock)
        self._ack_pub = node.session.declare_publisher(
            keys.lockstep_ack_key(node.vehicle), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )

    def register(self) -> None:
        self.node.declare_token(
            keys.lockstep_member_token(self.node.vehicle, self.node.name, self.node.publisher_id, self.trigger)
        )
        self.registered = True

    def poll_startup(self) -> None:
        """Before the first step: note whether the coordinator's pre-start clocks reach this member."""
        if not self.timed:
            if self._arrived:
                self.heard_coordinator = True
                self._arrived.clear()
            return
        sample = self._clock_sub.try_recv()
        while sample is not None:
            if self._clocks.decode(sample) is not None:
                self.heard_coordinator = True
            sample = self._clock_sub.try_recv()

    def ack_reachable(self) -> bool:
        """Whether this session knows the coordinator's acknowledgement subscriber (else an ack is lost)."""
        return self._ack_pub.matching_status.matching

    @property
    def rejected(self) -> int:
        return self._clocks.rejected

    def _on_clock(self, sample: zenoh.Sample) -> None:
        """Zenoh's thread: queue a triggered member's valid clocks."""
        clk = self._clocks.decode(sample)
        if clk is not None:
            self._arrived.append(clk)

    def _take(self, sample: zenoh.Sample) -> None:
        clk = self._clocks.decode(sample)
        if clk is not None:
            self._apply(clk)

    def _apply(self, clk: LockstepClock) -> None:
        if clk.step <= self.step:
            return
        self.members = frozenset(clk.members)
        self.admitted = self.node.publisher_id in self.members
        if self.admitted and self._floor is None:
            self._floor = {(pub, suffix): total for pub, suffix, total in clk.counts}
            self._continue_counts()
        floor = self._floor or {}
        require = self.barrier.require
        for pub, suffix, total in clk.counts:
            if total > floor.get((pub, suffix), 0):
                require(pub, suffix, total)
        self.step = clk.step
        self.now = clk.timestamp

    def _continue_counts(self) -> None:
        """A restarted member numbers its messages on from where its previous process stopped, so that
        every count the run keeps stays monotonic (the clock carries them)."""
        me = self.node.publisher_id
        assert self._floor is not None
        for pub in self.node.publishers:
            pub.count = max(pub.count, self._floor.get((me, pub.suffix), 0))

    def next_clock(self) -> None:
        """Block until the next tick and take it in (timed members); pre-start clocks are skipped."""
        step = self.step
        while self.step == step:
            self._take(self._clock_sub.recv())

    def advance_to(self, t: int) -> None:
        """Take in the newest clock, waiting until one has reached ``t`` (triggered members)."""
        arrived = self._arrived
        while arrived:
            self._apply(arrived.popleft())
        while self.now < t:
            self._apply(arrived.popleft() if arrived else self._slow_clock(t))

    def _slow_clock(self, t: int) -> LockstepClock:
        """Wait for the clock of time ``t``, saying so in the log if it is long in coming."""
        arrived = self._arrived
        started = time.monotonic()
        spins = 0
        while not arrived:
            spins += 1
            if spins < 100:
                time.sleep(0)
                continue
            if started and time.monotonic() - started > SLOW_WAIT_S:
                started = 0.0
                log.warning(
                    "lockstep: a trigger at t=%d us arrived but its clock has not after %.0f s (at t=%d us)",
                    t,
                    SLOW_WAIT_S,
                    self.now,
                )
            time.sleep(0.0002)
        return arrived.popleft()

    def ack(
        self, trigger_publisher: int, trigger_index: int, trigger_topic: str, touched: Iterable[TopicPublisher]
    ) -> None:
        if not self.admitted:
            return
        self._ack_pub.put(
            _encoder.encode(
                LockstepAck(
                    timestamp=self.now,
                    run=self.node.run_id,
                    member=self.node.name,
                    publisher_id=self.node.publisher_id,
                    trigger_publisher=trigger_publisher,
                    trigger_index=trigger_index,
                    trigger_topic=trigger_topic,
                    published=[(p.suffix, p.count) for p in touched],
                )
            )
        )

    def close(self) -> None:
        self._clock_sub.undeclare()
        self._ack_pub.undeclare()


@dataclass
class MemberToken:
    """What a member's lockstep token says of it (and, at the coordinator, when its timer last fired)."""

    name: str
    publisher_id: int
    trigger: str | None
    period_us: int | None
    last_fire: int | None = None


class LockstepCoordinator:
    """The driver side, used by the simulator. Call ``finish_step`` then ``begin_step`` each step."""

    def __init__(self, node: Node, own_inputs: Iterable[InputBuffer], stall_timeout_s: float = 10.0) -> None:
        self.node = node
        self._stall = StallWatch(stall_timeout_s)
        self.now = 0
        self.step = 0
        self.members: dict[int, MemberToken] = {}
        self.barrier = Barrier(own_inputs)
        self._triggered_by: dict[str, list[int]] = {}
        self._totals: dict[tuple[int, str], int] = {}
        # The participants' counters (see stack.runtime.ledger), kept from the acknowledgements: one list, and
        # where each counter is in it. A member's runs started are its runs finished (only those are heard of).
        self._counters: list[int] = []
        self._where: dict[tuple[object, ...], int] = {}
        self._bases: dict[tuple[int, int, str], int] = {}  # (member, publisher, topic) → count at admission
        self._ledger = StepLedger()
        self._tick_pubs: dict[int, zenoh.Publisher] = {}
        self._events: list[tuple[str, MemberToken]] = []
        self._events_lock = threading.Lock()
        self._waiting_since: float | None = None
        self._closed = threading.Event()
        self._departures = Departures()
        self._acks = ProtocolDecoder(LockstepAck, node.run_id, keys.lockstep_ack_key(node.vehicle))
        vehicle = node.vehicle
        self._clock_pub = node.session.declare_publisher(
            keys.lockstep_clock_key(vehicle), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        self._ack_key = keys.lockstep_ack_key(vehicle)
        self._ack_sub = node.session.declare_subscriber(self._ack_key, zenoh.handlers.FifoChannel(1 << 16))
        self._member_sub = node.session.liveliness().declare_subscriber(
            keys.lockstep_member_query(vehicle), self._on_member_token, history=True
        )
        self._watchdog = threading.Thread(target=self._watch, name="lockstep-watchdog", daemon=True)
        self._watchdog.start()

    @property
    def rejected(self) -> int:
        return self._acks.rejected

    # -- membership ---------------------------------------------------------------------------

    def _on_member_token(self, sample: zenoh.Sample) -> None:
        member = parse_member(str(sample.key_expr))
        if member is None:
            return
        kind = "join" if sample.kind == zenoh.SampleKind.PUT else "leave"
        with self._events_lock:
            self._events.append((kind, member))
        self._wake()

    def known_members(self) -> set[str]:
        with self._events_lock:
            joined = {m.name for kind, m in self._events if kind == "join"}
        return joined | {m.name for m in self.members.values()}

    def _apply_membership(self) -> None:
        with self._events_lock:
            events, self._events = self._events, []
        for kind, m in events:
            if kind == "join":
                if m.publisher_id in self.members:
                    # A liveliness subscriber with history can report a token declared while it
                    # started both from its history and live: count each member once.
                    continue
                self.members[m.publisher_id] = m
                self._departures.back(m.name)
                if m.trigger is not None:
                    self._triggered_by.setdefault(m.trigger, []).append(m.publisher_id)
                self._admit(m)
                log.info("lockstep member %s joined at t=%.3f s", m.name, self.now / 1e6)
            elif m.publisher_id in self.members:
                self._drop(m.publisher_id, f"lockstep member {m.name} left at t={self.now / 1e6:.3f} s")
                self._departures.left(m.name, time.monotonic())

    def _admit(self, m: MemberToken) -> None:
        """A (re)started member: its runs count from zero, and neither it nor its subscribers wait for messages
        written before it came."""
        me = m.publisher_id
        self._counters[self._counter("finished", me)] = 0
        self._counters[self._counter("ticks", me)] = 0
        for (publisher, suffix), total in self._totals.items():
            if publisher != me and suffix == m.trigger:
                self._bases[(me, publisher, suffix)] = total
            elif publisher == me:
                for member in self._triggered_by.get(suffix, ()):
                    self._bases[(member, me, suffix)] = total
        self._rebuild()

    def _drop(self, publisher_id: int, why: str) -> None:
        m = self.members.pop(publisher_id)
        tick = self._tick_pubs.pop(publisher_id, None)
        if tick is not None:
            tick.undeclare()
        if m.trigger is not None:
            self._triggered_by[m.trigger].remove(publisher_id)
        # A member killed between publishing and acknowledging leaves messages never announced: as it is no
        # longer a publisher of the ledger, nobody waits for them.
        self._rebuild()
        log.info("%s", why)  # the supervisor says whether the process failed

    def _counter(self, *key: object) -> int:
        """Where the counter ``key`` is in the list (a new one starts at zero)."""
        where = self._where.get(key)
        if where is None:
            where = self._where[key] = len(self._counters)
            self._counters.append(0)
        return where

    def _rebuild(self) -> None:
        """The ledger for the members now in the run and the publishers they take triggers from."""
        me = self.node.publisher_id
        publishers = {*self.members, me}
        timed, triggered = [], []
        for pid, m in self.members.items():
            finished = self._counter("finished", pid)
            if m.period_us is not None:
                timed.append(TimedMember(m.name, pid, finished, finished, self._counter("ticks", pid)))
            elif m.trigger is not None:
                sources = tuple(
                    TriggerSource(
                        self._counter("published", publisher, suffix),
                        self._counter("taken", pid, publisher),
                        self._bases.get((pid, publisher, suffix), 0),
                    )
                    for (publisher, suffix) in self._totals
                    if suffix == m.trigger and publisher != pid and publisher in publishers
                )
                triggered.append(TriggeredMember(m.name, pid, finished, finished, sources))
        self._ledger = StepLedger(timed, triggered)

    # -- the step -----------------------------------------------------------------------------

    def announce(self) -> None:
        """Before the first step: an empty clock (step 0) on the clock key and every timed member's tick
        key, so that members can tell the coordinator reaches them before they declare themselves synced."""
        self._apply_membership()
        clock = _encoder.encode(LockstepClock(timestamp=0, run=self.node.run_id, step=0, counts=[], members=[]))
        self._clock_pub.put(clock)
        for m in self.members.values():
            if m.period_us is not None:
                self._tick_publisher(m).put(clock)

    def begin_step(self, t: int) -> None:
        """Announce time ``t``: publish the clock. Publish this step's own messages right after."""
        self._apply_membership()
        if self._departures:
            self._await_restarts()
        self.now = t
        self.step += 1
        counts = [(pub, suffix, total) for (pub, suffix), total in self._totals.items()]
        member_ids = [*self.members, self.node.publisher_id]
        clock = _encoder.encode(
            LockstepClock(timestamp=t, run=self.node.run_id, step=self.step, counts=counts, members=member_ids)
        )
        self._clock_pub.put(clock)
        for m in self.members.values():
            if m.period_us is not None and timer_due(t, m.last_fire, m.period_us):
                m.last_fire = t
                self._counters[self._counter("ticks", m.publisher_id)] += 1
                self._tick_publisher(m).put(clock)

    def _await_restarts(self) -> None:
        """Time waits while a member that left is being restarted by the supervisor (asked every 50 ms)."""
        started = time.monotonic()
        logged = False
        while self._departures:
            states = module_states(self.node.session, self.node.vehicle)
            words = {name: supervisor_word(state) for name, state in states.items()}
            waiting = self._departures.awaited(lambda d, said=words: said.get(d.name, Word.NONE), time.monotonic())
            for name in self._departures.silent:
                log.warning("no word from the supervisor on %s: time goes on", name)
            if not waiting:
                return
            if not logged and time.monotonic() - started > SLOW_WAIT_S:
                logged = True
                log.warning("lockstep time waits at t=%.3f s for %s", self.now / 1e6, ", ".join(waiting))
            time.sleep(0.05)
            self._apply_membership()

    def _tick_publisher(self, m: MemberToken) -> zenoh.Publisher:
        pub = self._tick_pubs.get(m.publisher_id)
        if pub is None:
            pub = self.node.session.declare_publisher(
                keys.lockstep_tick_key(self.node.vehicle, m.name),
                congestion_control=zenoh.CongestionControl.BLOCK,
                express=True,
            )
            self._tick_pubs[m.publisher_id] = pub
        return pub

    def account_own(self, touched: Iterable[TopicPublisher]) -> None:
        """Count the coordinator's own publications of this step (call after publishing them)."""
        self._account(self.node.publisher_id, ((p.suffix, p.count) for p in touched))

    def _account(self, publisher_id: int, published: Iterable[tuple[str, int]]) -> None:
        counters, totals, new_source = self._counters, self._totals, False
        for suffix, total in published:
            if not isinstance(total, int) or total < 0:
                continue
            key = (publisher_id, suffix)
            if key not in totals:
                new_source = new_source or suffix in self._triggered_by
            totals[key] = total
            counters[self._counter("published", publisher_id, suffix)] = total
            self.barrier.require(publisher_id, suffix, total)
        if new_source:
            self._rebuild()

    def finish_step(self) -> None:
        """Block until every run the step caused has been acknowledged and its messages received."""
        self._waiting_since = time.monotonic()
        self._stall.start(self._waiting_since)
        try:
            while self._events or not self._ledger.complete(self._counters):
                self._apply_membership()
                if self._ledger.complete(self._counters):
                    break
                ack = self._acks.decode(self._ack_sub.recv())
                if ack is not None:
                    self._handle_ack(ack)
            self.barrier.wait()
        finally:
            self._waiting_since = None

    def _handle_ack(self, ack: LockstepAck) -> None:
        if ack.trigger_topic == _WAKE:
            self._check_stall()
            return
        sender = ack.publisher_id
        if sender not in self.members:
            return
        self._account(sender, ack.published)
        counters = self._counters
        counters[self._counter("finished", sender)] += 1
        if ack.trigger_topic != TIMER:
            taken = self._counter("taken", sender, ack.trigger_publisher)
            counters[taken] = max(counters[taken], ack.trigger_index)

    def _check_stall(self) -> None:
        self._stall.check(tuple(self._counters), time.monotonic(), self.now, self._busy)

    def _busy(self) -> list[str]:
        return [
            f"{m.name} ({self.members[m.key].trigger or TIMER})"
            for m, _ in self._ledger.with_work(self._counters)
            if m.key in self.members
        ]

    def _wake(self) -> None:
        self.node.session.put(self._ack_key, _encoder.encode(LockstepAck(run=self.node.run_id, trigger_topic=_WAKE)))

    def _watch(self) -> None:
        """Wake a coordinator whose step takes long, twice a second, to judge whether it still makes progress."""
        while not self._closed.wait(0.5):
            if self._waiting_since is not None and time.monotonic() - self._waiting_since > self._stall.timeout_s:
                self._wake()

    def close(self) -> None:
        self._closed.set()
        for pub in self._tick_pubs.values():
            pub.undeclare()
        self._member_sub.undeclare()
        self._ack_sub.undeclare()
        self._clock_pub.undeclare()


def supervisor_word(state: str) -> Word:
    """What a module's state in the supervisor's status says of a member that left (a module still "running"
    was restarted and not yet admitted, or its death not yet noticed: no word)."""
    if state in ("failed", "exited", "stopping"):
        return Word.GONE
    if state in ("restarting", "starting"):
        return Word.RESTARTING
    return Word.NONE


def parse_member(key: str) -> MemberToken | None:
    """``stack/<v>/@lockstep/member/<name>/<publisher_id>/topic/<topic>/<inst>`` or ``.../timer/<us>``."""
    parts = key.split("/")
    try:
        name, publisher_id, kind = parts[4], int(parts[5]), parts[6]
        if kind == "topic":
            return MemberToken(name, publisher_id, f"{parts[7]}/{int(parts[8])}", None)
        if kind == "timer":
            return MemberToken(name, publisher_id, None, int(parts[7]))
    except (IndexError, ValueError):
        pass
    log.warning("ignoring malformed lockstep member token %s", key)
    return None
