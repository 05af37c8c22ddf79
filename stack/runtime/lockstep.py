"""Lockstep: simulated time advances only when every module triggered by the last step is done.

This is PX4 SITL's lockstep (px4.md §4.5) spread over processes. One module, the simulator,
drives it as the *coordinator*; every other triggered or timed module is a *member*.

- Each member declares a liveliness token naming its trigger topic or its timer period.
- The coordinator publishes a clock message per step (the new time, the members expected to act,
  and the cumulative publication counts up to the previous step), then its own messages. Timed
  members receive the clock on their own key, and only on the steps their timer is due, so a 50 Hz
  module is not woken 250 times a second.
- A member runs once per trigger message (or per tick) and then acknowledges, reporting how many
  messages it published on each topic during that run.
- The coordinator keeps, per (member, trigger), the number of runs it still expects: it adds the
  runs each reported publication will cause and subtracts each acknowledgement. The step is done
  when every count is back to zero; only then does time advance.
- Before acting at time ``t`` a member waits until it holds every message the counts say was
  published before ``t`` (the *barrier*). With the visibility rules of :mod:`stack.runtime.inputs`
  this makes every run see the same inputs whatever the process scheduling, so lockstep runs with
  the same seed are identical.

A member that dies is dropped (and named) at once; one that stalls is named after a timeout and the
coordinator stops with an error rather than hang silently.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.node import Node
from stack.bus.topics import TopicPublisher
from stack.msg.internal import LockstepAck, LockstepClock
from stack.runtime.inputs import InputBuffer

log = logging.getLogger("stack.lockstep")

TIMER = "@timer"
CLOCK_RING = 8
SLOW_WAIT_S = 2.0
_WAKE = "@wake"
_clock_decoder = msgspec.msgpack.Decoder(LockstepClock)
_ack_decoder = msgspec.msgpack.Decoder(LockstepAck)
_encoder = msgspec.msgpack.Encoder()


class LockstepError(RuntimeError):
    """The lockstep cannot continue (a member stalled past the timeout)."""


def timer_due(t: int, last_fire: int | None, period_us: int) -> bool:
    """Timers fire on the first tick of each period-aligned interval; both sides use this rule."""
    return last_fire is None or t // period_us > last_fire // period_us


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
    trigger topic; its clock subscription is a small ring (the counts in each clock are cumulative,
    so older clocks may be dropped) read when a trigger arrives (``advance_to``). Neither is woken
    by clocks it does not need.
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
        if timed:
            self._clock_sub = node.session.declare_subscriber(
                keys.lockstep_tick_key(node.vehicle, node.name), zenoh.handlers.FifoChannel(4096)
            )
        else:
            self._clock_sub = node.session.declare_subscriber(
                keys.lockstep_clock_key(node.vehicle), zenoh.handlers.RingChannel(CLOCK_RING)
            )
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
        while self._clock_sub.try_recv() is not None:
            self.heard_coordinator = True

    def ack_reachable(self) -> bool:
        """Whether this session knows the coordinator's acknowledgement subscriber (else an ack is lost)."""
        return self._ack_pub.matching_status.matching

    def _take(self, clk: LockstepClock) -> None:
        require = self.barrier.require
        for pub, suffix, total in clk.counts:
            require(pub, suffix, total)
        self.members = frozenset(clk.members)
        self.admitted = self.node.publisher_id in self.members
        self.step = clk.step
        self.now = clk.timestamp

    def next_clock(self) -> None:
        """Block until the next tick and take it in (timed members); pre-start clocks are skipped."""
        while True:
            clk = _clock_decoder.decode(self._clock_sub.recv().payload.to_bytes())
            if clk.step > 0:
                self._take(clk)
                return

    def advance_to(self, t: int) -> None:
        """Take in the newest clock, waiting until one has reached ``t`` (triggered members)."""
        sub = self._clock_sub
        sample = sub.try_recv()
        while sample is not None:
            self._take(_clock_decoder.decode(sample.payload.to_bytes()))
            sample = sub.try_recv()
        while self.now < t:
            sample = sub.try_recv()
            if sample is None:
                sample = self._slow_clock(t)
            self._take(_clock_decoder.decode(sample.payload.to_bytes()))

    def _slow_clock(self, t: int) -> zenoh.Sample:
        """Block for the clock of time ``t``, saying so in the log if it is long in coming."""
        started = time.monotonic()
        spins = 0
        while True:
            sample = self._clock_sub.try_recv()
            if sample is not None:
                return sample
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

    def ack(self, trigger_publisher: int, trigger_topic: str, touched: Iterable[TopicPublisher]) -> None:
        if not self.admitted:
            return
        self._ack_pub.put(
            _encoder.encode(
                LockstepAck(
                    timestamp=self.now,
                    member=self.node.name,
                    publisher_id=self.node.publisher_id,
                    trigger_publisher=trigger_publisher,
                    trigger_topic=trigger_topic,
                    published=[(p.suffix, p.count) for p in touched],
                )
            )
        )

    def close(self) -> None:
        self._clock_sub.undeclare()
        self._ack_pub.undeclare()


@dataclass
class _Member:
    name: str
    publisher_id: int
    trigger: str | None
    period_us: int | None
    last_fire: int | None = None


class LockstepCoordinator:
    """The driver side, used by the simulator. Call ``finish_step`` then ``begin_step`` each step."""

    def __init__(self, node: Node, own_inputs: Iterable[InputBuffer], stall_timeout_s: float = 10.0) -> None:
        self.node = node
        self.stall_timeout_s = stall_timeout_s
        self.now = 0
        self.step = 0
        self.members: dict[int, _Member] = {}
        self.barrier = Barrier(own_inputs)
        self._triggered_by: dict[str, list[int]] = {}
        self._pending: dict[tuple[int, str], int] = {}
        self._totals: dict[tuple[int, str], int] = {}
        self._tick_pubs: dict[int, zenoh.Publisher] = {}
        self._events: list[tuple[str, _Member]] = []
        self._events_lock = threading.Lock()
        self._waiting_since: float | None = None
        self._closed = threading.Event()
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

    # -- membership ---------------------------------------------------------------------------

    def _on_member_token(self, sample: zenoh.Sample) -> None:
        member = _parse_member(str(sample.key_expr))
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
                if m.trigger is not None:
                    self._triggered_by.setdefault(m.trigger, []).append(m.publisher_id)
                log.info("lockstep member %s joined at t=%.3f s", m.name, self.now / 1e6)
            elif m.publisher_id in self.members:
                self._drop(m.publisher_id, f"lockstep member {m.name} left at t={self.now / 1e6:.3f} s")

    def _drop(self, publisher_id: int, why: str) -> None:
        m = self.members.pop(publisher_id)
        tick = self._tick_pubs.pop(publisher_id, None)
        if tick is not None:
            tick.undeclare()
        if m.trigger is not None:
            self._triggered_by[m.trigger].remove(publisher_id)
        for key in [k for k in self._pending if k[0] == publisher_id]:
            del self._pending[key]
        log.warning("%s", why)

    # -- the step -----------------------------------------------------------------------------

    def announce(self) -> None:
        """Before the first step: an empty clock (step 0) on the clock key and every timed member's tick
        key, so that members can tell the coordinator reaches them before they declare themselves synced."""
        self._apply_membership()
        clock = _encoder.encode(LockstepClock(timestamp=0, step=0, counts=[], members=[]))
        self._clock_pub.put(clock)
        for m in self.members.values():
            if m.period_us is not None:
                self._tick_publisher(m).put(clock)

    def begin_step(self, t: int) -> None:
        """Announce time ``t``: publish the clock. Publish this step's own messages right after."""
        self._apply_membership()
        self.now = t
        self.step += 1
        counts = [(pub, suffix, total) for (pub, suffix), total in self._totals.items()]
        member_ids = [*self.members, self.node.publisher_id]
        clock = _encoder.encode(LockstepClock(timestamp=t, step=self.step, counts=counts, members=member_ids))
        self._clock_pub.put(clock)
        for m in self.members.values():
            if m.period_us is not None and timer_due(t, m.last_fire, m.period_us):
                m.last_fire = t
                self._expect(m.publisher_id, TIMER, 1)
                self._tick_publisher(m).put(clock)

    def _tick_publisher(self, m: _Member) -> zenoh.Publisher:
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
        for suffix, total in published:
            key = (publisher_id, suffix)
            runs = total - self._totals.get(key, 0)
            self._totals[key] = total
            self.barrier.require(publisher_id, suffix, total)
            if runs > 0:
                for m in self._triggered_by.get(suffix, ()):
                    if m != publisher_id:
                        self._expect(m, suffix, runs)

    def _expect(self, member: int, what: str, n: int) -> None:
        key = (member, what)
        left = self._pending.get(key, 0) + n
        if left:
            self._pending[key] = left
        else:
            del self._pending[key]

    def finish_step(self) -> None:
        """Block until every run the step caused has been acknowledged and its messages received."""
        self._waiting_since = time.monotonic()
        try:
            while self._pending or self._events:
                self._apply_membership()
                if not self._pending:
                    break
                self._handle_ack(_ack_decoder.decode(self._ack_sub.recv().payload.to_bytes()))
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
        if ack.trigger_topic == TIMER:
            self._expect(sender, TIMER, -1)
        elif ack.trigger_publisher in self.members or ack.trigger_publisher == self.node.publisher_id:
            self._expect(sender, ack.trigger_topic, -1)

    def _check_stall(self) -> None:
        since = self._waiting_since
        if since is None or time.monotonic() - since < self.stall_timeout_s:
            return
        waiting = sorted({f"{self.members[m].name} ({what})" for (m, what) in self._pending if m in self.members})
        raise LockstepError(
            f"lockstep stalled at t={self.now / 1e6:.3f} s: no progress for {self.stall_timeout_s:.0f} s, "
            f"waiting for {', '.join(waiting)}"
        )

    def _wake(self) -> None:
        self.node.session.put(self._ack_key, _encoder.encode(LockstepAck(trigger_topic=_WAKE)))

    def _watch(self) -> None:
        while not self._closed.wait(0.5):
            if self._waiting_since is not None and time.monotonic() - self._waiting_since > self.stall_timeout_s:
                self._wake()

    def close(self) -> None:
        self._closed.set()
        for pub in self._tick_pubs.values():
            pub.undeclare()
        self._member_sub.undeclare()
        self._ack_sub.undeclare()
        self._clock_pub.undeclare()


def _parse_member(key: str) -> _Member | None:
    """``stack/<v>/@lockstep/member/<name>/<publisher_id>/topic/<topic>/<inst>`` or ``.../timer/<us>``."""
    parts = key.split("/")
    try:
        name, publisher_id, kind = parts[4], int(parts[5]), parts[6]
        if kind == "topic":
            return _Member(name, publisher_id, f"{parts[7]}/{int(parts[8])}", None)
        if kind == "timer":
            return _Member(name, publisher_id, None, int(parts[7]))
    except (IndexError, ValueError):
        pass
    log.warning("ignoring malformed lockstep member token %s", key)
    return None
