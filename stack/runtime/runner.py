"""The runtime that drives one module in its own process.

It opens the session, builds the module, serves its parameters, beats its heartbeat, follows or
drives the lockstep, runs the module once per trigger message or timer tick, and shuts down
cleanly, closing every Zenoh session (zenoh-python can hang at exit otherwise).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any

import zenoh

from stack.bus import keys
from stack.bus.access import Access
from stack.bus.alive import AliveTokens
from stack.bus.host_beats import beat_host, beats_key
from stack.bus.node import Node, wall_clock_us
from stack.bus.topics import FLAG_LOCKSTEP_TIME, Received, TopicPublisher, TopicSubscriber
from stack.fastpath.attach import Attachment
from stack.fastpath.bridge import ZenohBridge
from stack.fastpath.inputs import FastInput
from stack.fastpath.layout import SUB_QUEUE, SUB_TRIGGER, Region
from stack.msg.registry import ORB_ID, fingerprint
from stack.msg.system import ParameterUpdate
from stack.params.store import ParamStore
from stack.runtime import startup
from stack.runtime.fastrun import FastDriver, serve_group
from stack.runtime.inputs import InputBuffer, sample_time
from stack.runtime.lockstep import TIMER, LockstepCoordinator, LockstepMember
from stack.runtime.module import TRIGGER_BACKLOG, Module, Timer, Trigger
from stack.runtime.pacing import Pacer
from stack.runtime.peers import PeerInput
from stack.runtime.priority import highest_queue, raise_priority
from stack.runtime.realtime_group import serve_real_time_group
from stack.runtime.services import Heartbeat, ParamService
from stack.runtime.spec import ModuleSpec, load_module_class, resolve_args
from stack.runtime.start_deadline import StartDeadline
from stack.runtime.wall_timer import WallTimer
from stack.runtime.world_clock import world_clock

log = logging.getLogger("stack.runtime")

LOCKSTEP_QUEUE = 1 << 14
LATEST_RING = 8
# Outside messages reaching a fast-path module over Zenoh: decoded on arrival (garbage is dropped there)
# and queued, at most this many per input (a flood only displaces the flood's own oldest messages).
OUTSIDE_QUEUE = 1024
PASSIVE_NICENESS = 10


class Shutdown(BaseException):
    """Raised by the SIGTERM/SIGINT handler to unwind the loop and close the session."""


def shutdown_behind(error: BaseException) -> Shutdown | None:
    """The Shutdown that ``error`` was raised while handling, if any.

    A signal handler's exception can land inside threading's own lock code (a ``Condition.wait``
    re-acquiring its lock), which then fails with an error of its own (``release unlocked lock``)
    raised while the Shutdown unwinds: that is still a stop, not a crash.
    """
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, Shutdown):
            return seen
        seen = seen.__context__
    return None


def run_together(specs: list[ModuleSpec]) -> None:
    """Run several modules in this process (a profile's ``process = "NAME"``) until it is stopped: each is a module
    of its own, on one Zenoh session. Lockstep members of a fast-path run are served by one thread
    (:class:`stack.runtime.fastrun.ProcessGroup`), and so are the modules of a real-time run
    (:mod:`stack.runtime.realtime_group`)."""
    runtimes = [Runtime(spec, shares_process=True) for spec in specs]
    real_time = not specs[0].lockstep
    for rt in runtimes:
        if not real_time and not (rt.lockstep and rt.spec.fastpath_fd >= 0):
            raise ValueError(f"{rt.name}: only lockstep modules on the shared-memory fast path can share a process")
    queue = highest_queue(rt.module_cls.WORK_QUEUE for rt in runtimes)
    if real_time and queue is not None:
        # Before the session opens: its threads, which deliver every member's inputs, take the highest priority.
        raise_priority("+".join(rt.name for rt in runtimes), queue)
    with ExitStack() as stack:
        session: zenoh.Session | None = None
        for rt in runtimes:
            spec = rt.spec
            run_id = spec.run_id if spec.lockstep else 0
            node = Node(spec.bus, spec.vehicle, rt.name, clock=rt.now_us, run_id=run_id, session=session)
            session = node.session
            stack.callback(node.close)
            stack.callback(rt.close)
            rt.open(node)
        if real_time:
            serve_real_time_group(runtimes)
        else:
            serve_group([rt.fast_driver() for rt in runtimes])


class Runtime:
    def __init__(self, spec: ModuleSpec, shares_process: bool = False) -> None:
        self.spec = spec
        self.name = spec.name
        self.shares_process = shares_process
        """Other modules run in this process (:func:`run_together`), on the same thread in real time."""
        self.module_cls = load_module_class(spec.module)
        self.params = ParamStore(self.module_cls.PARAMS, spec.params)
        self.args = resolve_args(self.module_cls.ARGS, spec.args)
        self.lockstep = spec.lockstep and not self.module_cls.PASSIVE and not self.module_cls.OUTSIDE_LOCKSTEP
        self.inputs: dict[tuple[str, int], InputBuffer] = {}
        self.outputs: dict[tuple[str, int], TopicPublisher] = {}
        self.state = "starting"
        self.runs = 0
        self.errors = 0
        self.rejected = 0
        self.outside_triggers = 0
        self.behind = False
        self._now = 0
        self._loop_sum = 0.0
        self._loop_max = 0.0
        self._loop_runs = 0
        self._last_beat = time.monotonic()
        self._param_instance = 0
        self._trigger_buf: InputBuffer | None = None
        self.data: list[InputBuffer] = []
        """The inputs other than the trigger, once the module has declared them."""
        self._wall_data: list[InputBuffer] = []
        """The inputs a real-time run pulls, in that order (:meth:`_wall_inputs`), once the module has started."""
        self._last_sample = 0
        # The same-host fast path (stack.fastpath), when the supervisor gave this process its region.
        self.fast: Attachment | None = None
        self.trigger_input: FastInput | None = None
        self.reads_all_topics = False
        self._lockstep: LockstepMember | LockstepCoordinator | None = None
        self.bridge: ZenohBridge | None = None
        """A fast-path coordinator's members over Zenoh (stack.fastpath.bridge), whose rejected messages it counts."""
        self._region: Region | None = None
        self._services: list[ParamService | Heartbeat] = []
        self.node: Node
        self.module: Module
        self._module_watchers: list[zenoh.Subscriber] = []
        self.peer_inputs: dict[tuple[str, str], PeerInput] = {}
        self.access = Access.of(spec.vehicle, spec.peers, spec.open_topics) if spec.peers else None

    # -- clock -------------------------------------------------------------------------------------

    def now_us(self) -> int:
        return self._now if self.lockstep else wall_clock_us()

    # -- declarations used by Module -----------------------------------------------------------------

    def watch_modules(self, on_change: Callable[[str, int, bool], None]) -> None:
        """Call ``on_change(module, pid, alive)`` for every module process of this vehicle that is running or comes
        or goes (their liveliness tokens; called from a Zenoh thread). The subscriber lives as long as the session."""

        tokens = AliveTokens(self.spec.vehicle, log.warning)

        def changed(sample: zenoh.Sample) -> None:
            parsed = tokens.parse(str(sample.key_expr))
            if parsed is not None:
                on_change(*parsed, sample.kind == zenoh.SampleKind.PUT)

        key = keys.alive_query(self.spec.vehicle)
        self._module_watchers.append(self.node.session.liveliness().declare_subscriber(key, changed, history=True))

    def watch_hosts(self, on_beat: Callable[[str, bytes], None]) -> None:
        """Call ``on_beat(host, payload)`` for each beat of a host of this vehicle (stack.bus.host_beats; called from
        a Zenoh thread). The subscriber lives as long as the session."""
        vehicle = self.spec.vehicle

        def beat(sample: zenoh.Sample) -> None:
            host = beat_host(str(sample.key_expr), vehicle)
            if host is not None:
                on_beat(host, sample.payload.to_bytes())

        self._module_watchers.append(self.node.session.declare_subscriber(beats_key(vehicle), beat))

    def add_peer_input(self, vehicle: str, topic: str, delay_us: int) -> None:
        if vehicle == self.spec.vehicle:
            raise ValueError(f"{self.name}: {topic} of vehicle {vehicle} is this vehicle's own topic, not a peer's")
        if (vehicle, topic) not in self.peer_inputs:
            self.peer_inputs[(vehicle, topic)] = PeerInput(
                self.node, self.spec.bus, vehicle, topic, delay_us, self.lockstep
            )

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        if (topic, instance) in self.inputs:
            return
        if self.fast is not None:
            sub = self.node.subscriber(topic, instance, capacity=OUTSIDE_QUEUE, callback=True)
            self.fast.subscription(sub.suffix, SUB_QUEUE if queue else 0)
            keep = capacity if self.module_cls.PASSIVE and not self.module_cls.LOSSLESS else 0
            self.inputs[(topic, instance)] = self.guard(FastInput(self.fast.region, sub, queue, keep), topic)
            return
        if queue or self.lockstep:
            # In lockstep a latest-value input is a FIFO too, drained every run: a ring would let
            # dropped garbage push out the message the barrier waits for.
            sub = self.node.subscriber(topic, instance, capacity=max(capacity, LOCKSTEP_QUEUE if self.lockstep else 0))
        else:
            # Real time: the last few messages only; the newest is all a latest-value input needs. Decoded as they
            # arrive, so that a burst of garbage between two runs is counted in full.
            sub = self.node.subscriber(topic, instance, capacity=LATEST_RING, callback=True)
        self.inputs[(topic, instance)] = self.guard(InputBuffer(sub, queue, repeats=not self.lockstep), topic)

    def guard(self, buf: InputBuffer, topic: str) -> InputBuffer:
        """Tell ``buf`` whom it hears (:mod:`stack.bus.access`); an Offboard topic reads the control mode too."""
        if self.access is None or (rule := self.access.rule(topic)) == "anyone":
            return buf
        buf.members = self.access.publishers_of(topic)
        if rule == "offboard":
            self.add_input(ORB_ID.vehicle_control_mode.name, 0, False, 1)
            mode = self.inputs[(ORB_ID.vehicle_control_mode.name, 0)]
            buf.open_while = lambda: mode.latest is not None and mode.latest.flag_control_offboard_enabled
        return buf

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        if self.lockstep:
            reliable = True  # the barrier counts every message
        elif self.spec.placement:
            # A vehicle over several hosts, in real time: a message that waits for room in a full queue (on the way
            # to a ground host behind a slow link) holds up every router it passes, and with it the flight's own
            # traffic. PX4's uORB never blocks a publisher either: the message is dropped for that reader only.
            reliable = False
        pub = self.node.publisher(topic, instance, reliable=reliable)
        if self.fast is not None:
            sample = len(pub.encoder.encode(pub.msg_type()))
            pub.fast = self.fast.publication(pub.suffix, fingerprint(pub.msg_type), sample)
        self.outputs[(topic, instance)] = pub

    def read_all_topics(self) -> None:
        """A passive module that reads every topic of the run (the recorder): publishers never skip one."""
        self.reads_all_topics = True

    # -- lifecycle ---------------------------------------------------------------------------------

    def run(self, on_ready: Callable[[], None] | None = None) -> None:
        """Run the module until it stops; ``on_ready`` is called once it is up and about to loop."""
        spec = self.spec
        if not spec.lockstep and self.module_cls.WORK_QUEUE is not None:
            # Before the session opens, so that its threads (which deliver the inputs) inherit the priority.
            raise_priority(self.name, self.module_cls.WORK_QUEUE)
        run_id = spec.run_id if spec.lockstep else 0
        with Node(spec.bus, spec.vehicle, self.name, clock=self.now_us, run_id=run_id) as node:
            try:
                self.open(node)
                self.serve(on_ready)
            finally:
                self.close()

    def open(self, node: Node) -> None:
        """Everything but the loop, on the module's session: its shared memory (on the fast path), the module
        itself and its services (parameters, heartbeat). :meth:`close` undoes it, also when it failed half-way."""
        spec = self.spec
        self.node = node
        if self.lockstep:
            node.header_flags = FLAG_LOCKSTEP_TIME
        shm = spec.lockstep and spec.fastpath_fd >= 0
        if shm and not self.module_cls.OUTSIDE_LOCKSTEP:
            self._region = Region(spec.fastpath_fd)
        if self.module_cls.PASSIVE:
            # An observer yields to the control loops (a lossless one that falls far behind makes
            # lockstep time wait, see stack.fastpath.lockstep), yet still gets its share of a machine
            # loaded by other programs (SCHED_IDLE would starve it there, and the run with it).
            os.nice(PASSIVE_NICENESS)
        region = self._region
        if region is not None:
            if region.nonce != spec.run_id:
                raise ValueError(f"fd {spec.fastpath_fd} is the fast-path region of another run")
            self.fast = Attachment(region, self.name, node.publisher_id)
        self._declare_trigger()
        self.module = self.module_cls(self)
        self.data = self._data_inputs()
        self._param_pub = node.publisher(ORB_ID.parameter_update.name, reliable=self.lockstep)
        self._services.append(ParamService(node.session, node.vehicle, self.name, self.params))
        self._services.append(Heartbeat(node.session, node.vehicle, self.name, self.snapshot))

    def serve(self, on_ready: Callable[[], None] | None = None) -> None:
        """Say the module is up, then run it until it stops (on the fast path, on Zenoh's lockstep, or on the wall
        clock)."""
        if self.fast is not None:
            self.fast_driver(on_ready).run()
            return
        self._loop(self.start(on_ready))

    def start(self, on_ready: Callable[[], None] | None = None) -> LockstepMember | LockstepCoordinator | None:
        """Take the module's part in the lockstep, if any, and say it is up; returns that part, which its loop
        follows."""
        node, spec = self.node, self.spec
        self._wall_data = self._wall_inputs()
        lockstep_part = self._lockstep = self._make_lockstep()
        node.declare_token(keys.alive_token(node.vehicle, self.name, os.getpid()))
        # Over Zenoh the simulator starts once every module of the roster has synced; in a shared-memory run
        # it waits for the participants only, which a module outside the lockstep is not, nor an observer on
        # a host without the shared memory. An observer joining a running stack (`stack plot`, or a restart)
        # has nothing to wait for: nobody probes any more.
        cls = self.module_cls
        outside_run = spec.shm_run and (cls.OUTSIDE_LOCKSTEP or (cls.PASSIVE and spec.fastpath_fd < 0))
        observer_joining = cls.PASSIVE and spec.late_join
        if spec.lockstep and not outside_run and not observer_joining:
            self.state = "syncing"
            member = lockstep_part if isinstance(lockstep_part, LockstepMember) else None
            coordinator = lockstep_part if isinstance(lockstep_part, LockstepCoordinator) else None
            announce = coordinator.announce if coordinator is not None else None
            startup.sync(node, self.inputs.values(), member, spec, announce)
        self.state = "running"
        log.info("%s ready (%s)", self.name, self.describe_trigger())
        if on_ready is not None:
            on_ready()
        return lockstep_part

    def fast_driver(self, on_ready: Callable[[], None] | None = None) -> FastDriver:
        """The module's loop on the fast path; ``on_ready`` is called once it has taken its role."""
        node = self.node

        def announce() -> None:
            node.declare_token(keys.alive_token(node.vehicle, self.name, os.getpid()))
            self.state = "running"
            log.info("%s ready (%s, shared-memory fast path)", self.name, self.describe_trigger())
            if on_ready is not None:
                on_ready()

        return FastDriver(self, announce)

    def close(self) -> None:
        """Stop the module, then its services, its part in the lockstep and its shared memory (the session is
        the caller's)."""
        self.state = "stopping"
        module = getattr(self, "module", None)
        if module is not None:
            module.close()
        for peer in self.peer_inputs.values():
            peer.close()
        for service in self._services:
            service.close()
        if self._lockstep is not None:
            self._lockstep.close()
        if self._region is not None:
            self._region.close()

    def describe_trigger(self) -> str:
        trigger = self.module_cls.TRIGGER
        if self.module_cls.LOCKSTEP_COORDINATOR:
            return "lockstep coordinator" if self.lockstep else "real-time clock"
        if isinstance(trigger, Trigger):
            return f"on {trigger.name}"
        if isinstance(trigger, Timer):
            return f"every {trigger.period_us} us"
        return "no trigger"

    def _declare_trigger(self) -> None:
        trigger = self.module_cls.TRIGGER
        if not isinstance(trigger, Trigger):
            return
        if self.fast is not None:
            sub = self.node.subscriber(trigger.name, trigger.instance, capacity=OUTSIDE_QUEUE, callback=True)
            self.fast.subscription(sub.suffix, SUB_TRIGGER)
            self.trigger_input = FastInput(self.fast.region, sub, False)
            self._trigger_buf = self.guard(self.trigger_input, trigger.name)
            self.inputs[(trigger.name, trigger.instance)] = self._trigger_buf
            return
        if self.lockstep:
            sub = self.node.subscriber(trigger.name, trigger.instance, capacity=LOCKSTEP_QUEUE)
        else:
            # A module alone in its process waits on its trigger only: on Zenoh's ring. In a group one thread waits
            # for the triggers of all (stack.runtime.realtime_group): each sets the group's event.
            backlog = TRIGGER_BACKLOG if trigger.every else 4
            alone = not self.shares_process
            sub = self.node.subscriber(
                trigger.name, trigger.instance, capacity=backlog, keep_last=alone, callback=not alone
            )
        self._trigger_buf = self.guard(InputBuffer(sub, False), trigger.name)
        self.inputs[(trigger.name, trigger.instance)] = self._trigger_buf

    def _data_inputs(self) -> list[InputBuffer]:
        return [buf for buf in self.inputs.values() if buf is not self._trigger_buf]

    def _wall_inputs(self) -> list[InputBuffer]:
        """The data inputs in the order a real-time run pulls them: queues (commands) first. A command sent on
        seeing an input (MISSION_START on a mission_result) arrives after it; pulled the other way round, the
        input could land between its own pull and the command's, and the command would be judged without it."""
        return sorted(self._data_inputs(), key=lambda buf: not buf.queue_mode)

    def _make_lockstep(self) -> LockstepMember | LockstepCoordinator | None:
        if not self.lockstep:
            return None
        cls = self.module_cls
        if cls.LOCKSTEP_COORDINATOR:
            return LockstepCoordinator(self.node, self._data_inputs(), self.spec.stall_timeout_s)
        trigger = cls.TRIGGER
        if isinstance(trigger, Trigger):
            return LockstepMember(
                self.node, self._data_inputs(), f"topic/{trigger.name}/{trigger.instance}", timed=False
            )
        if isinstance(trigger, Timer):
            return LockstepMember(self.node, self._data_inputs(), f"timer/{trigger.period_us}", timed=True)
        return None

    # -- loops -----------------------------------------------------------------------------------------

    def _loop(self, part: LockstepMember | LockstepCoordinator | None) -> None:
        if isinstance(part, LockstepCoordinator):
            self._loop_coordinator(part)
        elif isinstance(part, LockstepMember):
            if isinstance(self.module_cls.TRIGGER, Trigger):
                self._loop_lockstep_trigger(part)
            else:
                self._loop_lockstep_timer(part)
        elif (period_us := self.wall_period_us()) is None:
            self._loop_wall_trigger()
        else:
            self._loop_wall_timer(period_us)

    def _loop_wall_trigger(self) -> None:
        buf = self._trigger_buf
        assert buf is not None
        while True:
            self.wall_trigger(buf.sub.recv())

    def _loop_wall_timer(self, period_us: int) -> None:
        timer = WallTimer(period_us, wall_clock_us())
        while True:
            delay = timer.next_due - wall_clock_us()
            if delay > 0:
                time.sleep(delay / 1e6)
            self.wall_tick(timer.fire(wall_clock_us()))

    # -- one run on the wall clock (its own loop's, or its process group's: stack.runtime.realtime_group) ------

    def wall_period_us(self) -> int | None:
        """How often the module runs on the wall clock; None if a trigger topic runs it."""
        cls = self.module_cls
        if cls.LOCKSTEP_COORDINATOR:
            return self.module.step_period_us()
        if isinstance(cls.TRIGGER, Timer):
            return cls.TRIGGER.period_us
        if isinstance(cls.TRIGGER, Trigger):
            return None
        raise RuntimeError(f"{cls.__name__} declares neither a trigger nor a timer")

    @property
    def trigger_subscriber(self) -> TopicSubscriber:
        assert self._trigger_buf is not None
        return self._trigger_buf.sub

    def wall_trigger(self, item: Received) -> None:
        """Run on a trigger message, with the newest of every input (real time)."""
        buf = self._trigger_buf
        assert buf is not None
        if not self._take_trigger(buf, item):
            return
        self.behind = bool(buf.sub.arrived)
        for d in self._wall_data:
            d.take_in_everything()
        self._last_sample = self._run(item.msg, sample_time(item.msg), self._last_sample)

    def wall_tick(self, now_us: int) -> None:
        """Run on a timer tick at ``now_us``, with the newest of every input (real time)."""
        for d in self._wall_data:
            d.take_in_everything()
        self._last_sample = self._run(None, now_us, self._last_sample)

    def _loop_lockstep_trigger(self, member: LockstepMember) -> None:
        buf = self._trigger_buf
        assert buf is not None
        suffix = buf.sub.suffix
        touched = self.node.touched
        while True:
            item = buf.sub.recv()
            if item.time_us < 0:
                self._ignore_outside_trigger(suffix)
                continue
            if item.index <= buf.last_index.get(item.publisher, 0):
                continue  # the same message again (put by its publisher and relayed: stack.fastpath.bridge)
            member.advance_to(item.time_us)
            member.barrier.wait()
            self.run_at(item.time_us, member.members, item)
            member.ack(item.publisher, item.index, suffix, touched)
            touched.clear()

    def _loop_lockstep_timer(self, member: LockstepMember) -> None:
        """The coordinator sends this member a tick on each step its timer is due."""
        touched = self.node.touched
        while True:
            member.next_clock()
            member.barrier.wait()
            self.run_at(member.now, member.members)
            member.ack(0, 0, TIMER, touched)
            touched.clear()

    def _loop_coordinator(self, coordinator: LockstepCoordinator) -> None:
        self._wait_for_synced_roster(coordinator)
        period = self.module.step_period_us()
        touched = self.node.touched
        pacer = Pacer(self.spec.speed)
        world = world_clock(self.spec, self.node.session)
        try:
            while True:
                coordinator.finish_step()
                if world is not None and coordinator.now:
                    world.done(coordinator.now)
                t = coordinator.now + period
                pacer.wait(t)
                if world is not None:
                    world.wait(t, period)
                coordinator.begin_step(t)
                self.run_at(t, frozenset((*coordinator.members, self.node.publisher_id)))
                coordinator.account_own(touched)
                touched.clear()
        finally:
            if world is not None:
                world.close()

    def _wait_for_synced_roster(self, coordinator: LockstepCoordinator) -> None:
        """Start only when every module of the roster has synced and every member has been admitted.

        A member declares its member token before its synced token, so once the synced tokens are
        visible the member tokens are too; the coordinator must also have taken them in.
        """
        self.state = "waiting for modules"
        deadline = StartDeadline()
        session, vehicle = self.node.session, self.node.vehicle
        while True:
            coordinator.announce()
            roster = startup.query_roster(self.node, self.spec.hosts) or {}
            synced = {
                str(r.ok.key_expr).rsplit("/", 1)[-1]
                for r in session.liveliness().get(keys.synced_query(vehicle), timeout=1.0)
                if r.ok is not None
            }
            members = {
                str(r.ok.key_expr).split("/")[4]
                for r in session.liveliness().get(keys.lockstep_member_query(vehicle), timeout=1.0)
                if r.ok is not None
            }
            missing = sorted((set(roster) - synced - {self.name}) | (members - coordinator.known_members()))
            if roster and not missing:
                break
            if deadline.passed(bool(roster)):
                raise RuntimeError(f"lockstep start timed out waiting for {', '.join(missing)}")
            time.sleep(0.02)
        self.state = "running"
        log.info("lockstep starting with %s", ", ".join(sorted(roster)))

    def _ignore_outside_trigger(self, suffix: str) -> None:
        """In lockstep only the run's own publishers trigger runs (time and triggers come from the run)."""
        self.rejected += 1
        self.outside_triggers += 1
        if self.outside_triggers == 1:
            log.warning("%s: ignoring messages from outside the lockstep run on its trigger %s", self.name, suffix)

    # -- one run ---------------------------------------------------------------------------------------

    def run_at(self, t: int, members: frozenset[int], trigger: Received | None = None) -> None:
        """One lockstep run at ``t`` of a run of ``members``, whatever the transport: on a timer tick (``trigger``
        None) or for one trigger message, with the inputs showing what the visibility rule lets it see."""
        self._now = t
        if trigger is None:
            for buf in self.data:
                buf.refresh(t, members)
            self._last_sample = self._run(None, t, self._last_sample)
            return
        assert self._trigger_buf is not None
        admitted = self._take_trigger(self._trigger_buf, trigger)
        for buf in self.data:
            buf.refresh(t, members, trigger.publisher, trigger.seq)
        if admitted:
            msg = trigger.msg
            self._last_sample = self._run(msg, sample_time(msg), self._last_sample)

    def _take_trigger(self, buf: InputBuffer, item: Received) -> bool:
        """Take a trigger message in; False if it is refused (the module does not run on it)."""
        buf.last_index[item.publisher] = item.index
        if not buf.admits(item.msg, item.publisher):
            return False
        buf.latest = item.msg
        return True

    def _run(self, msg: Any, sample_us: int, last_sample_us: int) -> int:
        changed = self.params.take_changes()
        if changed:
            self._announce_param_change(changed)
        lo, hi = self.module_cls.DT_RANGE
        dt = (sample_us - last_sample_us) * 1e-6 if last_sample_us else hi
        dt = lo if dt < lo else hi if dt > hi else dt
        t0 = time.perf_counter()
        try:
            self.module.run(msg, dt)
        except Exception:
            self.errors += 1
            if self.errors <= 10 or self.errors % 1000 == 0:
                log.exception("%s: run failed (%d so far); the module carries on", self.name, self.errors)
        elapsed = time.perf_counter() - t0
        self.runs += 1
        self._loop_sum += elapsed
        self._loop_runs += 1
        if elapsed > self._loop_max:
            self._loop_max = elapsed
        return sample_us

    def _announce_param_change(self, changed: set[str]) -> None:
        try:
            self.module.on_params_changed(changed)
        except Exception:
            log.exception("%s: applying parameters %s failed", self.name, sorted(changed))
        self._param_instance += 1
        log.info("parameters changed: %s", ", ".join(f"{n}={self.params[n]}" for n in sorted(changed)))
        self._param_pub.publish(
            ParameterUpdate(instance=self._param_instance, set_count=self.params.set_count, changed=len(changed)),
            self.now_us(),
        )

    # -- status --------------------------------------------------------------------------------------

    def snapshot(self) -> dict[str, Any]:
        now = time.monotonic()
        span = max(now - self._last_beat, 1e-3)
        runs = self._loop_runs
        avg = self._loop_sum / runs * 1e6 if runs else 0.0
        # Every subscriber's drops, inputs or not (a link's telemetry subscriptions, withdrawn ones too).
        decode, schema, foreign = self.node.drop_counts()
        status = {
            "state": self.state,
            "trigger": self.describe_trigger(),
            "runs": self.runs,
            "msgs_in": sum(buf.received for buf in self.inputs.values()),
            "msgs_out": sum(p.count for p in self.outputs.values()),
            "decode_errors": decode + sum(buf.ring_decode_errors for buf in self.inputs.values()),
            "schema_errors": schema,
            "foreign": foreign,
            "invalid": sum(buf.invalid for buf in self.inputs.values()),
            "unauthorized": sum(buf.unauthorized for buf in self.inputs.values()),
            "rejected": self.rejected
            + self.errors
            + (self._lockstep.rejected if self._lockstep else 0)
            + (self.bridge.rejected if self.bridge else 0),
            "loop_avg_us": avg,
            "loop_max_us": self._loop_max * 1e6,
            "trigger_rate_hz": runs / span,
            "sim_time_us": self._now if self.lockstep else 0,
        }
        module = getattr(self, "module", None)
        if module is not None:
            status["extra"] = module.status()
        self._loop_sum = 0.0
        self._loop_max = 0.0
        self._loop_runs = 0
        self._last_beat = now
        return status
