"""A whole launch profile in one process: the real module classes, an in-memory bus, the same lockstep.

Each module gets an :class:`InProcessRuntime`, a :class:`stack.runtime.runner.Runtime` whose inputs and
outputs are on the in-memory bus of :mod:`stack.runtime.membus` (it keeps the runner's run: parameter
changes, dt from ``timestamp_sample`` clamped to ``DT_RANGE``, a failing run logged and survived).
Passive modules (recorder, plot bridge) only observe and are left out. One lockstep step at time ``t``,
as :mod:`stack.runtime.lockstep` and :mod:`stack.fastpath` schedule it across processes:

1. the timed members whose timer is due (:func:`stack.runtime.ledger.timer_due`) run, in profile order;
2. the coordinator (the simulator) runs;
3. every message published on a module's trigger topic runs that module once, first published
   first run, until none is left (the runs of the step publish further triggers).

Each run sees exactly what :meth:`stack.runtime.inputs.InputBuffer.promote_visible` lets it see: every
message published before ``t``, plus, for a triggered run, its trigger publisher's earlier messages
of ``t``. That is why the order above gives the flight of the multi-process stack bit for bit: no
run's inputs depend on which of the other runs of the step came first, only the order of each
module's own runs matters, and each module runs its triggers in the order they were published (every
trigger topic of the shipped profiles has a single publisher).

A module that raises ``SystemExit`` leaves the run (the step finishes without it); when it is a
critical one, as the scenario of ``stack fly`` and the coordinator are, the run ends after that step,
as the supervisor stops the stack. Then every module is closed, in reverse start order.
"""

from __future__ import annotations

import functools
import logging
import time
from collections import deque
from collections.abc import Callable

from stack.bus.node import stable_publisher_id
from stack.bus.topics import Received
from stack.msg.registry import ORB_ID
from stack.runtime.inputs import InputBuffer
from stack.runtime.ledger import timer_due
from stack.runtime.membus import MemoryBus, MemoryInput, PublishedMessage
from stack.runtime.module import Timer, Trigger
from stack.runtime.runner import Runtime
from stack.runtime.spec import ModuleSpec
from stack.supervisor.profile import ModuleEntry, Profile

log = logging.getLogger("stack.runtime")


class InProcessRuntime(Runtime):
    """One module of an in-process run: what its module uses of a :class:`Runtime`, on the memory bus. Each message
    on its trigger topic goes to ``on_trigger`` (the run schedules the module's runs)."""

    def __init__(
        self,
        spec: ModuleSpec,
        bus: MemoryBus,
        critical: bool,
        on_trigger: Callable[[InProcessRuntime, Received], None],
    ) -> None:
        super().__init__(spec)
        self.bus = bus
        self.critical = critical
        self.publisher_id = stable_publisher_id(spec.vehicle, spec.name)
        self.seq = 0  # the publisher sequence, shared by all the module's topics
        self.last_fire: int | None = None
        self._subscribe_trigger(functools.partial(on_trigger, self))
        self.module = self.module_cls(self)
        self._param_pub = bus.publisher(self, ORB_ID.parameter_update.name, 0)
        self.data = self._data_inputs()

    def watch_modules(self, on_change: Callable[[str, int, bool], None]) -> None:
        """Nothing to watch: every module runs in this one process."""

    def watch_hosts(self, on_beat: Callable[[str, bytes], None]) -> None:
        """Nothing to watch: one process on one host."""

    def add_peer_input(self, vehicle: str, topic: str, delay_us: int) -> None:
        raise ValueError(f"{self.name}: one vehicle in one process reads no other vehicle ({vehicle}'s {topic})")

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        if (topic, instance) not in self.inputs:
            buf = MemoryInput(self.bus, self, topic, instance, queue)
            self.inputs[(topic, instance)] = self.guard(buf, topic)

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        self.outputs[(topic, instance)] = self.bus.publisher(self, topic, instance)

    def _subscribe_trigger(self, sink: Callable[[Received], None]) -> None:
        trigger = self.module_cls.TRIGGER
        if isinstance(trigger, Trigger) and not self.module_cls.LOCKSTEP_COORDINATOR:
            sub = self.bus.subscribe(self, trigger.name, trigger.instance, sink)
            self._trigger_buf = self.guard(InputBuffer(sub, False), trigger.name)  # type: ignore[arg-type]
            self.inputs[(trigger.name, trigger.instance)] = self._trigger_buf


def module_spec(profile: Profile, entry: ModuleEntry) -> ModuleSpec:
    """What the supervisor would tell the module's process (lockstep, the profile's vehicle and seed)."""
    return ModuleSpec(
        name=entry.name,
        module=entry.module,
        vehicle=profile.vehicle,
        bus=profile.bus,
        params=entry.params,
        args=entry.args,
        lockstep=True,
        seed=profile.seed,
        stall_timeout_s=profile.stall_timeout_s,
        peers=profile.publishers(),
        open_topics=list(profile.open_topics),
    )


class InProcessStack:
    """A profile's modules in this process, in lockstep: ``InProcessStack(profile).run()``.

    ``wire``: each subscriber decodes its own copy of a message from its msgpack bytes, as across
    processes (``False`` shares the published object). ``record``: keep every published message in
    ``published`` (topic, instance, publisher, index, time, flags and payload), as a recorder would.
    """

    def __init__(self, profile: Profile, *, wire: bool = True, record: bool = False) -> None:
        self.profile = profile
        self.bus = MemoryBus(wire=wire, record=record)
        self.runtimes: dict[str, InProcessRuntime] = {}
        self._triggers: deque[tuple[InProcessRuntime, Received]] = deque()
        for entry in profile.modules:
            if entry.cls.PASSIVE or entry.cls.OUTSIDE_LOCKSTEP:
                continue
            rt = InProcessRuntime(module_spec(profile, entry), self.bus, entry.critical, self._queue_trigger)
            self.runtimes[entry.name] = rt
        coordinators = [rt for rt in self.runtimes.values() if rt.module_cls.LOCKSTEP_COORDINATOR]
        if len(coordinators) != 1:
            raise ValueError(f"profile {profile.name}: expected one lockstep coordinator, found {len(coordinators)}")
        self.coordinator = coordinators[0]
        self.period_us = self.coordinator.module.step_period_us()
        self._timed = [
            (rt, rt.module_cls.TRIGGER.period_us)
            for rt in self.runtimes.values()
            if isinstance(rt.module_cls.TRIGGER, Timer)
        ]
        self._members = frozenset(rt.publisher_id for rt in self.runtimes.values())
        self.now_us = 0
        self.steps = 0
        self.step_cpu_s = 0.0
        self.running = True
        self.closed = False

    @property
    def published(self) -> list[PublishedMessage]:
        return self.bus.published

    def refused(self) -> dict[str, int]:
        """Messages each module input refused (``module:topic``: invalid or unauthorized), those that did."""
        counts = {
            f"{rt.name}:{topic}": buf.invalid + buf.unauthorized
            for rt in self.runtimes.values()
            for (topic, _), buf in rt.inputs.items()
        }
        return {key: n for key, n in counts.items() if n}

    def _queue_trigger(self, rt: InProcessRuntime, item: Received) -> None:
        self._triggers.append((rt, item))

    def step(self) -> None:
        """One lockstep step (see the module docstring)."""
        if not self.running:
            raise RuntimeError("the run has ended")
        t = self.now_us + self.period_us
        self.now_us = t
        self.steps += 1
        for rt, period_us in self._timed:
            if timer_due(t, rt.last_fire, period_us):
                rt.last_fire = t
                self._run(rt, t, None)
        self._run(self.coordinator, t, None)
        triggers = self._triggers
        while triggers:
            rt, item = triggers.popleft()
            self._run(rt, t, item)

    def _run(self, rt: InProcessRuntime, t: int, trigger: Received | None) -> None:
        """One run; a module that raises SystemExit leaves the run, and a critical one ends it after this step."""
        try:
            rt.run_at(t, self._members, trigger)
        except SystemExit as e:
            log.info("%s exited (code %s) at t=%.3f s", rt.name, e.code, t / 1e6)
            self._leave(rt)
            if rt.critical or rt is self.coordinator:
                self.running = False

    def _leave(self, rt: InProcessRuntime) -> None:
        del self.runtimes[rt.name]
        self.bus.unsubscribe_all(rt)
        self._timed = [m for m in self._timed if m[0] is not rt]
        kept = [item for item in self._triggers if item[0] is not rt]
        self._triggers.clear()
        self._triggers.extend(kept)
        rt.module.close()

    def run(self, max_steps: int | None = None) -> None:
        """Step until a critical module exits (or ``max_steps`` steps), then close every module.
        ``step_cpu_s`` is the process CPU time the steps took."""
        start = time.process_time()
        try:
            while self.running and (max_steps is None or self.steps < max_steps):
                self.step()
        finally:
            self.step_cpu_s += time.process_time() - start
            self.close()

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        for rt in reversed(list(self.runtimes.values())):
            rt.module.close()
