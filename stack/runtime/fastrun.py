"""The module loops of a fast-path run (see :mod:`stack.fastpath`): coordinator, members, passive readers."""

from __future__ import annotations

import os
import select
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

import msgspec

from stack.bus.topics import Received
from stack.fastpath.bridge import BridgedMember, ZenohBridge
from stack.fastpath.inputs import FastInput
from stack.fastpath.layout import (
    FLAG_LOSSLESS,
    FLAG_READS_ALL,
    H_NOW,
    H_TOPOLOGY,
    ROLE_COORDINATOR,
    ROLE_PASSIVE,
    ROLE_TIMED,
    ROLE_TRIGGERED,
    S_ADMIT_TIME,
    S_READ_TIME,
)
from stack.fastpath.lockstep import FastCoordinator, FastMember, drain
from stack.fastpath.ring import RingWriter, next_trigger, wake_all
from stack.fastpath.topology import Topology
from stack.runtime.module import Timer, Trigger
from stack.runtime.pacing import Pacer
from stack.runtime.world_clock import world_clock

if TYPE_CHECKING:
    from stack.runtime.runner import Runtime


class FastDriver:
    """Runs one module of a fast-path run until the process is stopped.

    After each run it wakes the members its records trigger, also when the run stopped the process (a
    scenario that ends, a coordinator at its last step): what a module wrote is always delivered.
    """

    def __init__(self, rt: Runtime, announce: Callable[[], None]) -> None:
        att = rt.fast
        assert att is not None
        self.rt = rt
        self._announce = announce
        """Says the module is alive: only once it is ready on the fast path, as the supervisor takes that word
        for the end of a restart, after which lockstep time stops waiting for it."""
        self.att = att
        self.region = att.region
        self.w = att.region.words
        self.topology_seen = -1
        self.topology: Topology | None = None
        self.members: frozenset[int] = frozenset()
        """The publisher ids of the run's admitted processes."""
        self.trigger = rt.trigger_input
        self.member = FastMember(att)
        self._consumed = [self.member.consumed_word(slot) for slot in range(self.region.slots)]
        self._decode_trigger = (
            msgspec.msgpack.Decoder(self.trigger.sub.msg_type).decode if self.trigger is not None else None
        )
        self.wake: Callable[[set[int]], None] = wake_all
        """Wakes the members this process's records trigger (a process group runs its own members directly)."""
        self.report_done: Callable[[list[RingWriter]], None] = self.member.done
        """Says a batch of runs is over, with the writers it used (a process group says so once per pass)."""

    # -- topology ----------------------------------------------------------------------------------

    def refresh_topology(self) -> None:
        """Re-read who is in the run if the coordinator changed it: rings to read, members to wake."""
        generation = self.w[H_TOPOLOGY]
        if generation == self.topology_seen:
            return
        topo = self.topology = Topology(self.region)
        self.topology_seen = topo.generation
        self.members = topo.publisher_ids
        me, since = self.att.slot, int(self.w[self.region.slot_word(self.att.slot, S_ADMIT_TIME)])
        for buf in self.rt.data:
            assert isinstance(buf, FastInput)
            buf.resolve(topo.sources(buf.hash), topo.publishers_of(buf.hash), since)
        if self.trigger is not None:
            # Trigger records count only from the publishers admitted now (so does the coordinator).
            self.trigger.readers = []
            self.trigger.resolve(topo.sources(self.trigger.hash, me), topo.publishers_of(self.trigger.hash), since)
            for r in self.trigger.readers:
                consumed = int(self.w[self.member.consumed_word(r.slot)])
                r.taken = max(r.taken, consumed, self.member.base(r.slot))
        for pub in self.rt.outputs.values():
            if pub.fast is not None:
                pub.fast_read = topo.read_by_anyone(pub.fast.topic, me)
                pub.fast.wake = topo.woken_by(pub.fast.topic, me)
        self.member.on_topology(topo)

    # -- loops -------------------------------------------------------------------------------------

    def ready(self) -> None:
        """Take this module's role in the run (its slot then counts as attached) and say it is alive."""
        cls = self.rt.module_cls
        if cls.LOCKSTEP_COORDINATOR:
            self.att.ready(ROLE_COORDINATOR)
        elif cls.PASSIVE:
            flags = (FLAG_LOSSLESS if cls.LOSSLESS else 0) | (FLAG_READS_ALL if self.rt.reads_all_topics else 0)
            self.att.ready(ROLE_PASSIVE, flags=flags)
        elif isinstance(cls.TRIGGER, Trigger):
            self.att.ready(ROLE_TRIGGERED, trigger=f"{cls.TRIGGER.name}/{cls.TRIGGER.instance}")
        elif isinstance(cls.TRIGGER, Timer):
            self.att.ready(ROLE_TIMED, period_us=cls.TRIGGER.period_us)
        else:
            raise RuntimeError(f"{cls.__name__} declares neither a trigger nor a timer")
        self._announce()

    def work(self) -> None:
        """A lockstep member's runs that are due (never blocks)."""
        if self.trigger is not None:
            self.work_triggered()
        else:
            self.work_timed()

    def run(self) -> None:
        """Take the role, then loop until the process is stopped."""
        self.ready()
        cls = self.rt.module_cls
        if cls.LOCKSTEP_COORDINATOR:
            self.run_coordinator()
        elif cls.PASSIVE:
            assert isinstance(cls.TRIGGER, Timer)
            self._run_passive(cls.TRIGGER.period_us)
        else:
            self._serve()

    def run_coordinator(self, others: Sequence[FastDriver] = ()) -> None:
        """Drive the run's steps; ``others`` are members sharing this process, run while the coordinator waits, as
        are the slots of the members over Zenoh (:mod:`stack.fastpath.bridge`)."""
        rt = self.rt
        bridged, stall_s = rt.spec.bridged, rt.spec.stall_timeout_s
        bridge = rt.bridge = ZenohBridge(rt.node, self.region, bridged, stall_s) if bridged else None
        beside = [*others, *(bridge.members if bridge is not None else ())]
        group = ProcessGroup(beside) if beside else None
        coordinator = FastCoordinator(self.att, rt.module.step_period_us(), rt.spec.stall_timeout_s, group)
        if group is not None:
            self.wake = group.wake
            group.beside_coordinator = True
        try:
            rt.state = "waiting for modules"
            if bridge is not None:
                bridge.join()
            coordinator.start()
            rt.state = "running"
            wakes = self.att.wakes
            pacer = Pacer(rt.spec.speed)
            world = world_clock(rt.spec, rt.node.session)
            while True:
                pacer.wait(coordinator.now + coordinator.period_us)
                if world is not None:
                    world.wait(coordinator.now + coordinator.period_us, coordinator.period_us)
                t = coordinator.begin_step()
                self.refresh_topology()
                try:
                    rt.run_at(t, self.members)
                finally:
                    if wakes:
                        self.wake(wakes)
                if group is not None:
                    group.pump()
                coordinator.finish_step()
                if world is not None:
                    world.done(t)
        finally:
            if world is not None:
                world.close()
            coordinator.close()
            if bridge is not None:
                bridge.close()

    def _serve(self) -> None:
        """A member's process: sleep until woken, then do what there is to do."""
        while True:
            self.member.wait()
            self.work()

    def _admitted(self) -> bool:
        if self.w[H_TOPOLOGY] != self.topology_seen:
            self.refresh_topology()
        return self.member.admitted()

    def work_timed(self) -> None:
        """Run every tick issued and not yet run, then tell the coordinator if the step may be over (never blocks)."""
        if not self._admitted():
            return
        rt, w, member = self.rt, self.w, self.member
        started, finished, ticks = member.started, member.finished, member.ticks
        wakes = self.att.wakes
        ran = w[ticks] > w[started]
        while w[ticks] > w[started]:
            w[started] += 1
            try:
                rt.run_at(int(w[H_NOW]), self.members)
            finally:
                if wakes:
                    self.wake(wakes)
            w[finished] += 1
        if ran:
            self._done()

    def work_triggered(self) -> None:
        """Run once per trigger record not yet taken, earliest first, then tell the coordinator if the step may be
        over (never blocks)."""
        if not self._admitted():
            return
        trigger = self.trigger
        assert trigger is not None
        if trigger.sub.arrived:
            self._drop_outside_triggers(trigger)
        rt, w, member = self.rt, self.w, self.member
        started, finished, consumed = member.started, member.finished, self._consumed
        decode, wakes = self._decode_trigger, self.att.wakes
        assert decode is not None
        ran = False
        while True:
            found = next_trigger(trigger.readers)
            if found is None:
                break
            ran = True
            reader, n, head = found
            w[started] += 1
            w[consumed[reader.slot]] = n
            reader.taken = n
            try:
                msg = decode(reader.payload(head.offset))
            except msgspec.DecodeError:
                msg = None
            if msg is None or not reader.still(n, head.offset):
                reader.lost += 1
                w[finished] += 1
                continue
            try:
                rt.run_at(head.time_us, self.members, Received(head.time_us, reader.publisher_id, head.seq, msg, n))
            finally:
                if wakes:
                    self.wake(wakes)
            w[finished] += 1
        if ran:
            self._done()

    def _done(self) -> None:
        touched = self.rt.node.touched
        self.report_done(fast_writers(touched))
        touched.clear()

    def _drop_outside_triggers(self, trigger: FastInput) -> None:
        """Triggers from outside the run are refused; the run's own records put on Zenoh for an outside subscriber
        (a ground-station link, ``stack topic echo``) arrive here too and are mere duplicates."""
        arrived = trigger.sub.arrived
        while arrived:
            item = arrived.popleft()
            if not trigger.from_inside(item):
                self.rt._ignore_outside_trigger(trigger.sub.suffix)

    def _run_passive(self, period_us: int) -> None:
        """A passive module runs on its wall-clock timer, or sooner when the coordinator wakes a lossless
        reader that fell behind (it marks how far it has read itself: see stack.fastpath.alltopics)."""
        rt, w = self.rt, self.w
        poll = select.poll()
        poll.register(self.att.eventfd, select.POLLIN)
        read_time = self.region.slot_word(self.att.slot, S_READ_TIME)
        last = 0
        while True:
            if poll.poll(period_us // 1000):
                drain(self.att.eventfd)
            self.refresh_topology()
            now = int(w[H_NOW])
            for buf in rt.data:
                buf.refresh(now, self.members)
            if rt.data:
                w[read_time] = now
            last = rt._run(None, rt.now_us(), last)


class ProcessGroup:
    """Lockstep members sharing one process (``process = "NAME"`` in a profile), each still its own module with
    its slot, topics, parameters and heartbeat.

    One thread serves them all: it sleeps until any of their eventfds is written, then runs the members woken,
    in the profile's order, until none is left, and then tells the coordinator once that the step may be over.
    A member woken by another of the group is marked, not sent a wake-up, and runs in the same pass; the
    coordinator, when it is in the group, runs them while it waits for the step to end.
    """

    def __init__(self, drivers: Sequence[FastDriver | BridgedMember]) -> None:
        self.drivers = list(drivers)
        self.eventfds = [d.att.eventfd for d in self.drivers]
        self.beside_coordinator = False
        """The coordinator shares the process: it reads the counters itself once the group has run."""
        self._local = frozenset(self.eventfds)
        self._pending: set[int] = set()
        self._ran = False
        self._writers: list[RingWriter] = []
        for d in self.drivers:
            d.wake = self.wake
            d.report_done = self._collect

    def _collect(self, writers: list[RingWriter]) -> None:
        self._ran = True
        self._writers.extend(writers)

    def mark(self, fd: int) -> None:
        """Wake a member of the group: it runs in the next pass."""
        self._pending.add(fd)

    def wake(self, wakes: set[int]) -> None:
        for fd in wakes:
            if fd in self._local:
                self._pending.add(fd)
            else:
                os.eventfd_write(fd, 1)
        wakes.clear()

    def pump(self, woken: Iterable[int] = ()) -> None:
        """Run the members woken (their eventfds ``woken`` and those marked) until none is left."""
        pending = self._pending
        pending.update(woken)
        while pending:
            for d in self.drivers:
                fd = d.att.eventfd
                if fd in pending:
                    pending.discard(fd)
                    d.work()
        if self._ran:
            # The pass is over, every member idle: the step may be over (see FastMember.done), said once.
            writers, self._ran, self._writers = self._writers, False, []
            if not self.beside_coordinator:
                self.drivers[0].member.done(writers)

    def serve(self) -> None:
        poll = select.poll()
        for fd in self.eventfds:
            poll.register(fd, select.POLLIN)
        while True:
            woken = [fd for fd, _ in poll.poll()]
            for fd in woken:
                drain(fd)
            self.pump(woken)


def serve_group(drivers: Sequence[FastDriver]) -> None:
    """Run modules sharing a process until it is stopped: each takes its role, then the coordinator (if one is
    among them) drives the run and runs the others while it waits, or the others serve together."""
    members = [d for d in drivers if not d.rt.module_cls.LOCKSTEP_COORDINATOR]
    for d in members:
        d.ready()
    coordinator = next((d for d in drivers if d.rt.module_cls.LOCKSTEP_COORDINATOR), None)
    if coordinator is not None:
        coordinator.ready()
        coordinator.run_coordinator(members)
    else:
        ProcessGroup(members).serve()


def fast_writers(touched: set[Any]) -> list[Any]:
    return [pub.fast for pub in touched if pub.fast is not None and pub.fast.wake]
