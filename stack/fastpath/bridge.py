"""Members of a fast-path run that take part over Zenoh: one lockstep, two transports.

A module a profile gives ``transport = "zenoh"`` (as a module on another host must) keeps a slot in the
run's region like every member, but its process never maps the region: it is a Zenoh lockstep member
(:class:`stack.runtime.lockstep.LockstepMember`), unchanged. The coordinator's process serves its slot
(:class:`BridgedMember`, run beside the coordinator as the members of its process group are), so the
coordinator, the step ledger and every other member see one more member of the fast path:

- when the slot is ticked, or one of its trigger records is due, the bridge puts on Zenoh, in order of
  publication, every record of the fast path's modules that the member subscribes to and has not been
  sent yet (with the publisher's own header: its id, sequence number, topic index and time); then a
  :class:`~stack.msg.internal.LockstepClock` whose counts are what was sent, so the member's barrier
  waits for exactly those; a trigger reaches the member as it would over Zenoh alone, as one of them;
- the member runs, publishes on Zenoh (where tools and members over Zenoh read it) and acknowledges; the
  acknowledgement wakes the slot, and the bridge writes the publications it counts into the slot's rings,
  waking the fast members they trigger, and only then counts the run finished. The coordinator's process
  never waits on one member: members over Zenoh run side by side, as processes of the fast path do.

The visibility rule is the same on both sides (:func:`stack.runtime.inputs.visible`), so a run mixing the
transports publishes the same messages, bit for bit, as the run on one transport. At start-up the bridge
plays the part the fast path's modules do not play over Zenoh: it sends the pre-start clocks and the
probes of the fast publishers whose topics a member reads, waits for the member's own probes, and says
the coordinator is synced once every slot is ready. A member that leaves (its lockstep token goes) is
named; time waits while the supervisor restarts it, as for any member, and its runs are skipped while it
is gone for good. One that stops acknowledging is a member whose run does not end: the coordinator's stall
verdict names it.
"""

from __future__ import annotations

import heapq
import logging
import os
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.node import Node, stable_publisher_id
from stack.bus.supervisors import module_states
from stack.bus.topics import FLAG_LOCKSTEP_TIME, FLAG_PROBE, HEADER
from stack.fastpath.attach import Attachment
from stack.fastpath.layout import (
    H_NOW,
    H_ROSTER,
    H_STEP,
    H_TOPOLOGY,
    P_FINGERPRINT,
    ROLE_TIMED,
    ROLE_TRIGGERED,
    S_EXITS,
    S_RESTART,
    SUB_TRIGGER,
    Region,
    topic_hash,
)
from stack.fastpath.lockstep import FastMember
from stack.fastpath.ring import RingReader, RingWriter, next_trigger, wake_all
from stack.fastpath.topology import Topology
from stack.msg.internal import LockstepAck, LockstepClock
from stack.msg.registry import UnknownTopic, message_type
from stack.runtime.ledger import SLOW_WAIT_S, VERDICT_TIMEOUT_S, LockstepError, Word
from stack.runtime.lockstep import (
    TIMER,
    MemberToken,
    ProtocolDecoder,
    parse_member,
    supervisor_word,
)
from stack.runtime.start_deadline import StartDeadline

log = logging.getLogger("stack.lockstep")

RESTART_POLL_S = 0.05
WAKE_CHECK_S = 0.05
"""How often a wait for a member over Zenoh looks again whether it left or stalled."""
REJOIN_SETTLE_S = 0.5
"""A member back after a restart: how long its subscriptions are given to reach the bridge's session."""
_encoder = msgspec.msgpack.Encoder()


@dataclass(order=True)
class _Relayed:
    """A fast-path record on its way to the members over Zenoh, in order of publication."""

    time_us: int
    publisher_id: int
    seq: int
    index: int = field(compare=False)
    suffix: str = field(compare=False)
    fingerprint: int = field(compare=False)
    payload: bytes = field(compare=False)


@dataclass
class _Sample:
    index: int
    time_us: int
    seq: int
    payload: bytes


class BridgedMember:
    """One member over Zenoh, as a slot of the fast path served in the coordinator's process (the shape of a
    :class:`stack.runtime.fastrun.FastDriver` to a process group: ``att``, ``member``, ``wake``, ``report_done``,
    ``work``)."""

    def __init__(self, bridge: ZenohBridge, name: str) -> None:
        self.bridge = bridge
        self.name = name
        self.publisher_id = stable_publisher_id(bridge.vehicle, name)
        self.att = Attachment(bridge.region, name, self.publisher_id)
        self.member = FastMember(self.att)
        self.w = bridge.region.words
        self.wake: Callable[[set[int]], None] = wake_all
        self.report_done: Callable[[list[RingWriter]], None] = self.member.done
        self.trigger = ""
        """``topic/instance`` of its trigger, empty for a timed member."""
        self.period_us = 0
        self.subs: list[str] = []
        self.writers: dict[str, RingWriter] = {}
        self._samples: dict[str, list[_Sample]] = {}
        self._raw: list[zenoh.Subscriber] = []
        self._probed: set[str] = set()
        self._cond = bridge.cond
        self.token: MemberToken | None = None
        """What its lockstep token says, once it is in (Zenoh's thread)."""
        self.declared = False
        self.ready = False
        self.present = False
        self._left_at: float | None = None
        """When it left (monotonic seconds), while it is gone."""
        self._given_up = False
        """Gone and not waited for any more: its runs are skipped until it is back."""
        self._exits = 0
        """The supervisor's count of the module's exits when it was admitted (its word is a higher count)."""
        self._back_at = 0.0
        self._missed: dict[tuple[int, str], int] = {}
        """What was sent before it came back, which its new process never received: those triggers are skipped."""
        self._acks: dict[tuple[int, int], LockstepAck] = {}
        self._ticks_acked: list[LockstepAck] = []
        self._readers: list[RingReader] = []
        self._topology_seen = -1
        self._running: tuple[int, tuple[int, int] | None] | None = None
        """The run forwarded and not acknowledged yet: its time, and its trigger (publisher id, index) or None."""
        self.rejected = 0

    # -- start-up ----------------------------------------------------------------------------------

    def declare(self, trigger: str | None, period_us: int | None, pubs: dict[str, int], subs: list[str]) -> None:
        """Fill the slot with what the member's tokens say: its trigger or timer, publications and subscriptions."""
        session, vehicle = self.bridge.session, self.bridge.vehicle
        self.trigger, self.period_us = trigger or "", period_us or 0
        for suffix, fp in pubs.items():
            topic, _, instance = suffix.partition("/")
            try:
                sample = len(_encoder.encode(message_type(topic)()))
            except UnknownTopic:
                sample = 256
            self.writers[suffix] = self.att.publication(suffix, fp, sample)
            self._samples[suffix] = []
            key = keys.topic_key(vehicle, topic, int(instance))
            self._raw.append(session.declare_subscriber(key, lambda s, suffix=suffix: self._on_sample(suffix, s)))
        for suffix in subs:
            self.att.subscription(suffix, SUB_TRIGGER if suffix == self.trigger else 0)
        self.subs = subs
        self.declared = True

    def probes_seen(self) -> bool:
        with self._cond:
            return self._probed >= set(self.writers)

    def take_role(self) -> None:
        self._exits = self._exits_now()
        if self.trigger:
            self.att.ready(ROLE_TRIGGERED, trigger=self.trigger)
        else:
            self.att.ready(ROLE_TIMED, period_us=self.period_us)
        self.ready = self.present = True

    def _on_sample(self, suffix: str, sample: zenoh.Sample) -> None:
        """Zenoh's thread: keep the member's own publications of this run (anything else is counted)."""
        attachment = sample.attachment
        raw = attachment.to_bytes() if attachment is not None else b""
        if len(raw) != HEADER.size:
            return  # not from a stack publisher: never the member's
        _, pub_id, seq, index, pub_time, flags, run = HEADER.unpack(raw)
        if pub_id != self.publisher_id:
            return  # another publisher of the topic (the fast path's own, a tool's)
        if run != self.bridge.run_id:
            self.rejected += 1
            return
        with self._cond:
            if flags & FLAG_PROBE:
                self._probed.add(suffix)
            elif flags & FLAG_LOCKSTEP_TIME:
                self._samples[suffix].append(_Sample(index, pub_time, seq, sample.payload.to_bytes()))
                self._cond.notify_all()

    # -- membership --------------------------------------------------------------------------------

    def left(self) -> None:
        """Its lockstep token went: the process died or stopped (Zenoh's thread)."""
        if not self.present:
            return
        with self._cond:
            self.present = False
        self._left_at = time.monotonic()
        self._given_up = False
        log.info("lockstep member %s left at t=%.3f s (over Zenoh)", self.name, self.w[H_NOW] / 1e6)
        os.eventfd_write(self.att.eventfd, 1)

    def back(self) -> None:
        if self.present or not self.ready:
            return
        self._exits = self._exits_now()
        self._missed = dict(self.bridge.published)
        self.present = True
        self._left_at = None
        self._back_at = time.monotonic()
        with self._cond:
            self._acks.clear()
            self._ticks_acked.clear()
            for samples in self._samples.values():
                samples.clear()
        log.info("lockstep member %s joined at t=%.3f s (over Zenoh)", self.name, self.w[H_NOW] / 1e6)

    def _exits_now(self) -> int:
        return int(self.w[self.bridge.region.slot_word(self.att.slot, S_EXITS)])

    def _word(self) -> Word:
        """The supervisor's word on the member that left: restarting, gone, or none yet."""
        region = self.bridge.region
        if self._exits_now() <= self._exits:
            return Word.NONE
        return Word.RESTARTING if self.w[region.slot_word(self.att.slot, S_RESTART)] else Word.GONE

    def _await_return(self) -> bool:
        """A run due while the member is gone: wait while the supervisor restarts it; True once it is back.

        The region's word that no restart is pending comes both when the restarts were given up and when the new
        process is up but has not joined yet (over Zenoh it syncs first): the supervisor's status tells which,
        and time waits at most VERDICT_TIMEOUT_S more for the member's token."""
        logged = False
        over_at: float | None = None
        while not self.present:
            left_at = self._left_at
            if left_at is None or self._given_up:
                return self.present
            word = self._word()
            now = time.monotonic()
            if word is Word.GONE and over_at is None:
                over_at = now
                state = module_states(self.bridge.session, self.bridge.vehicle).get(self.name, "")
                if supervisor_word(state) is Word.GONE:
                    over_at = -VERDICT_TIMEOUT_S  # it failed or exited for good
            if (over_at is not None and now - over_at > VERDICT_TIMEOUT_S) or (
                word is Word.NONE and now - left_at > VERDICT_TIMEOUT_S
            ):
                self._given_up = True
                log.warning("lockstep time goes on at t=%.3f s without %s", self.w[H_NOW] / 1e6, self.name)
                return False
            if not logged and now - left_at > SLOW_WAIT_S:
                logged = True
                log.warning("lockstep time waits at t=%.3f s for %s to restart", self.w[H_NOW] / 1e6, self.name)
            time.sleep(RESTART_POLL_S)
        return True

    # -- runs --------------------------------------------------------------------------------------

    def refresh_topology(self) -> None:
        region, w = self.bridge.region, self.w
        generation = w[H_TOPOLOGY]
        if generation == self._topology_seen:
            return
        self._topology_seen = int(generation)
        topo = Topology(region)
        me = self.att.slot
        for suffix, writer in self.writers.items():
            writer.wake = topo.woken_by(topic_hash(suffix), me)
        if self.trigger:
            known = {(r.slot, r.entry): r for r in self._readers}
            readers = []
            for source in topo.sources(topic_hash(self.trigger), me):
                r = RingReader(region, source.slot, source.publication, source.publisher_id)
                old = known.get((r.slot, r.entry))
                consumed = int(w[self.member.consumed_word(r.slot)])
                r.taken = max(old.taken if old is not None else 0, consumed, self.member.base(r.slot))
                readers.append(r)
            self._readers = readers
        self.member.on_topology(topo)

    def work(self) -> None:
        """Finish the run the member has acknowledged, then forward the next one due (never blocks on the member:
        its acknowledgement, or its leaving, writes the slot's eventfd, and the coordinator's process calls this
        again)."""
        if self.w[H_TOPOLOGY] != self._topology_seen:
            self.refresh_topology()
        if not self.member.admitted():
            return
        w, member = self.w, self.member
        ran = False
        while True:
            if self._running is not None:
                if not self._finish():
                    break
                ran = True
            t, trigger = 0, None
            if not self.trigger:
                if w[member.ticks] <= w[member.started]:
                    break
                t = int(w[H_NOW])
            else:
                found = next_trigger(self._readers)
                if found is None:
                    break
                reader, n, head = found
                w[member.consumed_word(reader.slot)] = n
                reader.taken = n
                t, trigger = head.time_us, (reader.publisher_id, head.index)
            w[member.started] += 1
            self._running = (t, trigger)
            if not self._forward(t, trigger):
                self._running = None
                w[member.finished] += 1
                ran = True
        if ran:
            self.report_done([writer for writer in self.writers.values() if writer.wake])

    def _forward(self, t: int, trigger: tuple[int, int] | None) -> bool:
        """Send the member what it reads and the clock of this run; False if the run is skipped."""
        if not self.present and not self._await_return():
            return False  # gone: the run is skipped (its trigger is taken, nothing is published)
        if trigger is not None and trigger[1] <= self._missed.get((trigger[0], self.trigger), 0):
            return False  # sent before its new process came: never received
        if time.monotonic() - self._back_at < REJOIN_SETTLE_S:
            time.sleep(max(0.0, REJOIN_SETTLE_S - (time.monotonic() - self._back_at)))
        self.bridge.send_clock(t, None if self.trigger else self.name)
        return True

    def _finish(self) -> bool:
        """End the run in progress if the member acknowledged it (writing what it published) or left."""
        assert self._running is not None
        _, trigger = self._running
        with self._cond:
            if trigger is None:
                ack = self._ticks_acked.pop(0) if self._ticks_acked else None
            else:
                ack = self._acks.pop(trigger, None)
            if ack is None and self.present:
                return False
        if ack is not None:
            self._take_publications(ack)
        self._running = None
        self.w[self.member.finished] += 1
        return True

    def on_ack(self, ack: LockstepAck) -> None:
        """Zenoh's thread: keep the acknowledgement and wake the slot."""
        with self._cond:
            if ack.trigger_topic == TIMER:
                self._ticks_acked.append(ack)
            else:
                self._acks[(ack.trigger_publisher, ack.trigger_index)] = ack
        os.eventfd_write(self.att.eventfd, 1)

    def _take_publications(self, ack: LockstepAck) -> None:
        """Write into the slot's rings the messages the acknowledgement counts (waiting for the last to arrive)."""
        started = time.monotonic()
        for suffix, total in ack.published:
            writer = self.writers.get(suffix)
            if writer is None:
                raise LockstepError(f"{self.name} (over Zenoh) published {suffix}, which it had not declared")
            if not isinstance(total, int):
                continue
            with self._cond:
                while True:
                    samples = self._samples[suffix]
                    if samples and samples[-1].index >= total:
                        self._samples[suffix] = []
                        break
                    if not self.present or time.monotonic() - started > self.bridge.stall_timeout_s:
                        raise LockstepError(
                            f"{self.name} (over Zenoh): {suffix} #{total} acknowledged but never received"
                        )
                    self._cond.wait(WAKE_CHECK_S)
            for s in samples:
                writer.write(s.payload, s.index, s.time_us, s.seq)
                self.bridge.published[(self.publisher_id, suffix)] = s.index
        wakes = self.att.wakes
        if wakes:
            self.wake(wakes)

    def close(self) -> None:
        for sub in self._raw:
            sub.undeclare()


class ZenohBridge:
    """The members over Zenoh of a fast-path run, served in the coordinator's process on its session."""

    def __init__(self, node: Node, region: Region, names: Iterable[str], stall_timeout_s: float) -> None:
        self.node = node
        self.session = node.session
        self.vehicle = node.vehicle
        self.run_id = node.run_id
        self.region = region
        self.stall_timeout_s = stall_timeout_s
        self.cond = threading.Condition()
        self.members = [BridgedMember(self, name) for name in names]
        self._by_id = {m.publisher_id: m for m in self.members}
        self._by_name = {m.name: m for m in self.members}
        self.published: dict[tuple[int, str], int] = {}
        """(publisher id, ``topic/instance``) → the last index sent to the members or taken from them."""
        self._relays: dict[str, zenoh.Publisher] = {}
        self._readers: list[tuple[RingReader, str]] = []
        self._topology_seen = -1
        self._clock_step = -1
        self._clock_pub = self.session.declare_publisher(
            keys.lockstep_clock_key(self.vehicle), congestion_control=zenoh.CongestionControl.BLOCK, express=True
        )
        self._tick_pubs = {
            m.name: self.session.declare_publisher(
                keys.lockstep_tick_key(self.vehicle, m.name),
                congestion_control=zenoh.CongestionControl.BLOCK,
                express=True,
            )
            for m in self.members
        }
        self._acks = ProtocolDecoder(LockstepAck, self.run_id, keys.lockstep_ack_key(self.vehicle))
        self._ack_sub = self.session.declare_subscriber(keys.lockstep_ack_key(self.vehicle), self._on_ack)
        self._graph: dict[tuple[str, str, str], int] = {}
        """(module, ``pub`` or ``sub``, ``topic/instance``) → schema fingerprint, from the topic graph's tokens."""
        self._graph_sub = self.session.liveliness().declare_subscriber(
            keys.graph_query(self.vehicle), self._on_graph_token, history=True
        )
        self._member_sub = self.session.liveliness().declare_subscriber(
            keys.lockstep_member_query(self.vehicle), self._on_member_token, history=True
        )
        self._synced = False

    @property
    def rejected(self) -> int:
        return self._acks.rejected + sum(m.rejected for m in self.members)

    # -- start-up ----------------------------------------------------------------------------------

    def join(self) -> None:
        """Block until every member over Zenoh has a ready slot and has synced (see the module docstring)."""
        deadline = StartDeadline()
        step0 = _encoder.encode(LockstepClock(timestamp=0, run=self.run_id, step=0, counts=[], members=[]))
        while True:
            self._clock_pub.put(step0)
            for pub in self._tick_pubs.values():
                pub.put(step0)
            for m in self.members:
                with self.cond:
                    token = m.token
                    mine = {(role, suffix): fp for (who, role, suffix), fp in self._graph.items() if who == m.name}
                if m.declared or token is None:
                    continue
                pubs = {suffix: fp for (role, suffix), fp in mine.items() if role == "pub"}
                subs = sorted(suffix for role, suffix in mine if role == "sub")
                m.declare(token.trigger, token.period_us, pubs, subs)
                for suffix in subs:
                    self._relay(suffix)
            self._probe()
            for m in self.members:
                if m.declared and not m.ready and m.probes_seen():
                    m.take_role()
            waiting = [m.name for m in self.members if not m.ready]
            if not waiting:
                if not self._synced:
                    self.node.declare_token(keys.synced_token(self.vehicle, self.node.name))  # the node undeclares it
                    self._synced = True
                synced = {
                    str(r.ok.key_expr).rsplit("/", 1)[-1]
                    for r in self.session.liveliness().get(keys.synced_query(self.vehicle), timeout=0.5)
                    if r.ok is not None
                }
                waiting = [m.name for m in self.members if m.name not in synced]
                if not waiting:
                    log.info("lockstep members over Zenoh: %s", ", ".join(m.name for m in self.members))
                    return
            if deadline.passed(bool(self.region.words[H_ROSTER])):
                raise LockstepError(f"lockstep start timed out waiting for {', '.join(waiting)} (over Zenoh)")
            time.sleep(0.02)

    def _relay(self, suffix: str) -> None:
        if suffix not in self._relays:
            topic, _, instance = suffix.partition("/")
            self._relays[suffix] = self.session.declare_publisher(
                keys.topic_key(self.vehicle, topic, int(instance)),
                congestion_control=zenoh.CongestionControl.BLOCK,
                express=True,
            )

    def _probe(self) -> None:
        """Probes of the fast path's publishers of what the members read: their messages reach the members through
        this session, which the probes show they can (:mod:`stack.runtime.startup`)."""
        with self.cond:
            publishers = [(m, s, fp) for (m, role, s), fp in self._graph.items() if role == "pub" and s in self._relays]
        for module, suffix, fp in publishers:
            if module not in self._by_name:
                pid = stable_publisher_id(self.vehicle, module)
                self._relays[suffix].put(b"", attachment=HEADER.pack(fp, pid, 0, 0, 0, FLAG_PROBE, self.run_id))

    def _on_graph_token(self, sample: zenoh.Sample) -> None:
        """Zenoh's thread: ``stack/<vehicle>/@graph/<module>/<role>/<topic>/<instance>/<Type>/<fingerprint>``.

        A member's graph tokens are declared before its lockstep token, on one session, and arrive here in that
        order: once its lockstep token is in, so are its publications and subscriptions."""
        parts = str(sample.key_expr).split("/")
        if len(parts) != 9 or parts[4] not in ("pub", "sub"):
            return
        try:
            key, fp = (parts[3], parts[4], f"{parts[5]}/{int(parts[6])}"), int(parts[8], 16)
        except ValueError:
            return
        with self.cond:
            if sample.kind == zenoh.SampleKind.PUT:
                self._graph[key] = fp
            else:
                self._graph.pop(key, None)

    def _on_member_token(self, sample: zenoh.Sample) -> None:
        parsed = parse_member(str(sample.key_expr))
        m = self._by_name.get(parsed.name) if parsed is not None else None
        if m is None or parsed is None or parsed.publisher_id != m.publisher_id:
            return
        if sample.kind != zenoh.SampleKind.PUT:
            m.left()
        elif m.ready:
            m.back()
        else:
            with self.cond:
                m.token = parsed

    # -- runs --------------------------------------------------------------------------------------

    def send_clock(self, t: int, tick: str | None) -> None:
        """Put on Zenoh what the members read and has not been sent, then the clock of ``t`` counting it: on a timed
        member's tick key (``tick``), or on the clock key once per step."""
        self._relay_records()
        step = int(self.region.words[H_STEP])
        if tick is None and step == self._clock_step:
            return
        clock = _encoder.encode(
            LockstepClock(
                timestamp=t,
                run=self.run_id,
                step=step,
                counts=[(pub, suffix, total) for (pub, suffix), total in self.published.items()],
                members=sorted(Topology(self.region).publisher_ids),
            )
        )
        if tick is None:
            self._clock_step = step
            self._clock_pub.put(clock)
        else:
            self._tick_pubs[tick].put(clock)

    def _refresh_readers(self) -> None:
        w = self.region.words
        if w[H_TOPOLOGY] == self._topology_seen:
            return
        self._topology_seen = int(w[H_TOPOLOGY])
        topo = Topology(self.region)
        known = {(r.slot, r.entry): r for r, _ in self._readers}
        bridged = {m.att.slot for m in self.members}
        readers = []
        for suffix in self._relays:
            for source in topo.sources(topic_hash(suffix)):
                if source.slot in bridged:
                    continue  # a member over Zenoh publishes there itself
                r = RingReader(self.region, source.slot, source.publication, source.publisher_id)
                old = known.get((r.slot, r.entry))
                r.taken = old.taken if old is not None else 0
                readers.append((r, suffix))
        self._readers = readers

    def _relay_records(self) -> None:
        """Every record of the fast path's modules a member reads and not yet sent, in order of publication."""
        self._refresh_readers()
        batch: list[_Relayed] = []
        for r, suffix in self._readers:
            taken = r.take_new()
            if taken:
                fp = int(self.region.words[r.entry + P_FINGERPRINT])
                batch.extend(_Relayed(h.time_us, r.publisher_id, h.seq, h.index, suffix, fp, p) for h, p in taken)
        heapq.heapify(batch)
        published, relays, run = self.published, self._relays, self.run_id
        while batch:
            rec = heapq.heappop(batch)
            header = HEADER.pack(
                rec.fingerprint, rec.publisher_id, rec.seq, rec.index, rec.time_us, FLAG_LOCKSTEP_TIME, run
            )
            relays[rec.suffix].put(rec.payload, attachment=header)
            published[(rec.publisher_id, rec.suffix)] = rec.index

    def _on_ack(self, sample: zenoh.Sample) -> None:
        """Zenoh's thread: hand an acknowledgement to its member."""
        ack = self._acks.decode(sample)
        m = self._by_id.get(ack.publisher_id) if ack is not None else None
        if ack is not None and m is not None and ack.member == m.name:
            m.on_ack(ack)

    def close(self) -> None:
        for m in self.members:
            m.close()
        self._member_sub.undeclare()
        self._graph_sub.undeclare()
        self._ack_sub.undeclare()
        self._clock_pub.undeclare()
        for pub in (*self._tick_pubs.values(), *self._relays.values()):
            pub.undeclare()
