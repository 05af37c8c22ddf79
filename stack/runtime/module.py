"""The base class of every module, after PX4's work items.

A module says what triggers it, what it reads and publishes, and which parameters and arguments
it takes; the runtime does the rest (session, lockstep, parameters service, heartbeat, shutdown)::

    class MulticopterRateControl(Module):
        NAME = "mc_rate_control"
        TRIGGER = Trigger(ORB_ID.vehicle_angular_velocity)
        DT_RANGE = (0.000125, 0.02)
        PARAMS = catalogue.params("MC_ROLLRATE_P", ...)   # definitions from stack.params.catalogue
        PUBLISHES = (ORB_ID.vehicle_torque_setpoint,)     # all it may publish

        def __init__(self, ctx):
            super().__init__(ctx)
            self.subscribe(ORB_ID.vehicle_rates_setpoint)
            self.advertise(ORB_ID.vehicle_torque_setpoint)
            self.control = RateControl(...)          # the plain algorithm class

        def run(self, msg, dt):
            sp = self.latest(ORB_ID.vehicle_rates_setpoint)   # a VehicleRatesSetpoint, or None
            ...
            self.publish(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(...))

The algorithm itself is a plain class with no Zenoh in it; the module is thin glue. Topics are named by their
handles (:class:`stack.msg.registry.ORB_ID`), which carry their message types: a topic's name is a string only
where it meets the outside (bus keys, recordings, the CLI).
"""

from __future__ import annotations

import json
import logging
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

from stack.msg.base import Message
from stack.msg.registry import ORB_ID
from stack.msg.topic import Topic, topic_name
from stack.params.param import Param, ParamError, ParamValue, convert
from stack.runtime.priority import WorkQueue

LINK_SUFFIX = ".link"
"""A module's link for the user (see :meth:`Module.show_link`) is the file ``<run dir>/<module><LINK_SUFFIX>``."""

if TYPE_CHECKING:
    from stack.runtime.runner import Runtime

M = TypeVar("M", bound=Message)


TRIGGER_BACKLOG = 256
"""Trigger messages a real-time ``Trigger(every=True)`` module keeps while behind: a second of a 250 Hz IMU."""
KEEP_PERIOD_US = 200_000
"""How often a module whose state changes every run (an estimator) keeps it for an instance restarted after a
crash: in lockstep the kept state is at most this old when it resumes (simulated time waits for the restart)."""
KEEP_WRITE_PERIOD_S = 0.2
"""And at most this often on the wall clock: a lockstep run ten times faster than real time would otherwise write
each estimator's file 50 times a second."""


RUNTIME_PUBLISHES = (ORB_ID.parameter_update,)
"""What a module's runtime publishes for it: its parameters as they change (PX4's ``parameter_update``)."""


@dataclass(frozen=True)
class Trigger:
    """Run once per message published on this topic.

    In real time a module that falls behind (a busy machine) skips to the newest messages, as a controller should;
    with ``every`` it runs on each message of the backlog in order (up to ``TRIGGER_BACKLOG``), as an estimator
    integrating its gyro must (a gyro sample skipped is a rotation lost), and :meth:`Module.behind` tells it to
    leave the publishing to the newest.
    """

    topic: Topic
    instance: int = 0
    every: bool = False

    def __post_init__(self) -> None:
        topic_name(self.topic)

    @property
    def name(self) -> str:
        return self.topic.name


@dataclass(frozen=True)
class Timer:
    """Run periodically (on simulated time in lockstep, on the wall clock otherwise)."""

    hz: float

    @property
    def period_us(self) -> int:
        return round(1e6 / self.hz)


@dataclass(frozen=True)
class Arg:
    """A launch argument: configuration fixed for the life of the process (unlike a parameter)."""

    name: str
    default: ParamValue
    doc: str = ""
    choices: tuple[ParamValue, ...] = ()

    def check(self, value: object) -> ParamValue:
        where = f"argument {self.name}"
        v = convert(where, type(self.default), value)
        if self.choices and v not in self.choices:
            raise ParamError(f"{where}: {v!r} is not one of {', '.join(repr(c) for c in self.choices)}")
        return v


class Module:
    NAME: ClassVar[str] = ""
    DESCRIPTION: ClassVar[str] = ""
    TRIGGER: ClassVar[Trigger | Timer | None] = None
    PARAMS: ClassVar[tuple[Param, ...]] = ()
    ARGS: ClassVar[tuple[Arg, ...]] = ()
    PUBLISHES: ClassVar[tuple[Topic, ...]] = ()
    """The topics the module may publish (any instance): :meth:`advertise` refuses any other, a module reading a topic
    hears it from the modules declaring it only (stack.bus.access), and a vehicle's host may put on another host's
    router only its own modules' topics (stack.security.acl)."""
    # PX4 clamps each module's dt, e.g. to 0.125–20 ms in MulticopterRateControl::Run and 0.2–20 ms in
    # MulticopterAttitudeControl::Run; (min, max) in seconds.
    DT_RANGE: ClassVar[tuple[float, float]] = (0.0002, 0.02)
    # The lockstep coordinator (the simulator) drives time instead of following it.
    LOCKSTEP_COORDINATOR: ClassVar[bool] = False
    # A passive module (recorder, plot bridge) only observes: it never joins the lockstep, runs on the
    # wall clock, and the simulation does not wait for it. It still syncs at start so it misses nothing.
    PASSIVE: ClassVar[bool] = False
    # A passive module that must not lose messages (the recorder): on the same-host fast path,
    # lockstep time waits for it whenever it falls far behind.
    LOSSLESS: ClassVar[bool] = False
    # A module outside the lockstep even in a lockstep run, like a program that is not part of the stack (a
    # ground-station link): it runs on the wall clock, reads and publishes over Zenoh only (never on the
    # same-host fast path), and stamps what it publishes with the simulated time it has seen. It links the
    # stack to the world outside (fixed ports), so the scripted flights of `stack fly` do not start it.
    OUTSIDE_LOCKSTEP: ClassVar[bool] = False
    # The PX4 work queue whose priority the module's process takes on the wall clock (stack.runtime.priority);
    # None: normal priority.
    WORK_QUEUE: ClassVar[WorkQueue | None] = None

    def __init__(self, rt: Runtime) -> None:
        self.rt = rt
        self.params = rt.params
        self.args: dict[str, ParamValue] = rt.args
        self.log = logging.getLogger(rt.name)
        self._kept: dict[str, Any] | None = None
        self._kept_at_us = 0
        self._kept_at_s = 0.0

    @classmethod
    def publishes(cls, args: Mapping[str, ParamValue]) -> frozenset[str]:
        """The names of the topics the module publishes with launch arguments ``args``: its PUBLISHES and what its
        runtime publishes for it (a module whose outputs depend on its arguments says so here, from the arguments
        alone, without I/O)."""
        return frozenset(topic_name(t) for t in (*RUNTIME_PUBLISHES, *cls.PUBLISHES))

    # -- declarations (call from __init__) -------------------------------------------------------

    def subscribe(self, topic: Topic, instance: int = 0, *, queue: bool = False, capacity: int = 256) -> None:
        """Read a topic: the latest value, or with ``queue=True`` every message (for commands)."""
        self.rt.add_input(topic_name(topic), instance, queue, capacity)

    def subscribe_peer(self, vehicle: str, topic: Topic, delay_s: float) -> None:
        """Read another vehicle's topic on the bus, each message ``delay_s`` after it was published (as over a swarm's
        radio; see stack.runtime.peers); :meth:`peer` gives it."""
        self.rt.add_peer_input(vehicle, topic_name(topic), round(delay_s * 1e6))

    def advertise(self, topic: Topic, instance: int = 0, *, reliable: bool | None = None) -> None:
        """Publish a topic the module declares it publishes (:meth:`publishes`)."""
        name = topic_name(topic)
        if name not in self.publishes(self.args):
            declared = f"{type(self).__name__}.PUBLISHES"
            raise ValueError(f"{self.rt.name} advertises {name}, which {declared} does not declare")
        self.rt.add_output(name, instance, reliable)

    # -- use (from run) ----------------------------------------------------------------------------

    def latest(self, topic: Topic[M], instance: int = 0) -> M | None:
        """The newest message visible now, or None if none has been received."""
        return self.rt.inputs[(topic.name, instance)].latest

    def update(self, topic: Topic[M], instance: int = 0) -> M | None:
        """The newest message if it arrived since the previous call, else None."""
        return self.rt.inputs[(topic.name, instance)].update()

    def take(self, topic: Topic[M], instance: int = 0) -> list[M]:
        """Every message that arrived since the previous call, oldest first (``queue=True`` inputs)."""
        return self.rt.inputs[(topic.name, instance)].take()

    def peer(self, vehicle: str, topic: Topic[M]) -> M | None:
        """The message of another vehicle's topic due now (see :meth:`subscribe_peer`), or None before its first."""
        return self.rt.peer_inputs[(vehicle, topic.name)].read(self.rt.now_us())

    def peer_present(self, vehicle: str, topic: Topic) -> bool:
        """Whether any module of that vehicle is running (its processes are on the bus)."""
        return self.rt.peer_inputs[(vehicle, topic.name)].present()

    def publish(self, topic: Topic[M], msg: M, instance: int = 0) -> None:
        self.rt.outputs[(topic.name, instance)].publish(msg, self.rt.now_us())

    def now_us(self) -> int:
        return self.rt.now_us()

    def behind(self) -> bool:
        """In real time, more trigger messages are already waiting (``Trigger(every=True)``); never in lockstep."""
        return self.rt.behind

    def reject(self, what: str) -> None:
        """Count and log an input the module refused (bad setpoint, out-of-range command...)."""
        self.rt.rejected += 1
        self.log.warning("rejected: %s", what)

    # -- hooks -------------------------------------------------------------------------------------

    def on_params_changed(self, changed: set[str]) -> None:
        """Called between runs with the names of parameters that changed."""

    def run(self, msg: Any, dt: float) -> None:
        """One run: ``msg`` is the trigger message (None for timers); ``dt`` is clamped to DT_RANGE."""
        raise NotImplementedError

    def step_period_us(self) -> int:
        """The lockstep coordinator's step (its simulated-time tick), in µs."""
        raise NotImplementedError

    def status(self) -> dict[str, float | int | str | bool]:
        """Figures of the module's own for its heartbeat (called from the heartbeat thread)."""
        return {}

    def watch_modules(self, on_change: Callable[[str, int, bool], None]) -> None:
        """``on_change(module, pid, alive)`` for each module process of this vehicle as it runs, starts or dies
        (called from another thread)."""
        self.rt.watch_modules(on_change)

    def watch_hosts(self, on_beat: Callable[[str, bytes], None]) -> None:
        """``on_beat(host, payload)`` for each beat of a host of this vehicle, when it is spread over hosts
        (stack.bus.host_beats; called from another thread)."""
        self.rt.watch_hosts(on_beat)

    def show_link(self, what: str, url: str) -> None:
        """Give the user a link (a web viewer's page): logged now, and said again by the supervisor once the
        whole stack is up, as its last start-up line, where it is seen."""
        self.log.info("%s: %s", what, url)
        if self.rt.spec.run_dir:
            (Path(self.rt.spec.run_dir) / f"{self.rt.spec.name}{LINK_SUFFIX}").write_text(f"{what}: {url}")

    def keep_due(self) -> bool:
        """Whether a module whose state changes every run keeps it now (then call :meth:`keep_state`): every
        KEEP_PERIOD_US of its time, at most every KEEP_WRITE_PERIOD_S of the wall clock."""
        now_us, now_s = self.now_us(), time.monotonic()
        if now_us - self._kept_at_us < KEEP_PERIOD_US or now_s - self._kept_at_s < KEEP_WRITE_PERIOD_S:
            return False
        self._kept_at_us, self._kept_at_s = now_us, now_s
        return True

    def keep_state(self, state: dict[str, Any]) -> None:
        """Keep what an instance restarted after a crash resumes from (JSON, in the run directory; written
        atomically, and only when it changed)."""
        if state == self._kept or not self.rt.spec.run_dir:
            return
        self._kept = state
        path = Path(self.rt.spec.run_dir) / f"{self.rt.spec.name}.resume.json"
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(state))
        os.replace(tmp, path)

    def kept_state(self) -> dict[str, Any] | None:
        """What the previous instance kept, when this one is a restart; None on a first start (or if unreadable)."""
        if not self.rt.spec.late_join or not self.rt.spec.run_dir:
            return None
        path = Path(self.rt.spec.run_dir) / f"{self.rt.spec.name}.resume.json"
        try:
            state = json.loads(path.read_text())
        except (OSError, ValueError):
            return None
        return state if isinstance(state, dict) else None

    def close(self) -> None:
        """Release resources (the runtime closes the session itself)."""
