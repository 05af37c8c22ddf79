"""What a flight script sees: time, the latest topics, commands with their acknowledgements, waits.

A script is a generator function taking a :class:`ScriptContext`. It yields to wait (``yield
ctx.wait(2.0)``, ``yield ctx.until(lambda: ..., timeout=5)``) and uses the context to publish
setpoints and commands. It only talks to the stack over the bus, as any user's script would.
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from typing import Any, TypeVar

from stack.msg.base import Message
from stack.msg.registry import ORB_ID
from stack.msg.system import RESULT_NAMES, VehicleCommand, VehicleCommandAck, command_label
from stack.msg.topic import Topic

M = TypeVar("M", bound=Message)
Wait = Callable[[], bool]
Script = Callable[["ScriptContext"], Generator[Wait, None, None]]


class ScenarioError(RuntimeError):
    """The scenario could not go on (a command was refused, a wait timed out)."""


@dataclass
class Series:
    """A recorded signal: sample times [s] and values."""

    times: list[float] = field(default_factory=list)
    values: list[Any] = field(default_factory=list)

    def add(self, t: float, value: Any) -> None:
        self.times.append(t)
        self.values.append(value)

    def between(self, t0: float, t1: float) -> list[Any]:
        return [v for t, v in zip(self.times, self.values, strict=True) if t0 <= t <= t1]


@dataclass(frozen=True)
class SwarmRole:
    """A vehicle's place in a swarm flight: its slot (1: the leader), the vehicles by slot, the spacing of their
    homes (each ``spacing_m`` east of the one before, stack.supervisor.swarm)."""

    slot: int
    vehicles: tuple[str, ...]
    spacing_m: float

    @property
    def leader(self) -> str:
        return self.vehicles[0]

    @property
    def leads(self) -> bool:
        return self.slot == 1


class LatestMessages:
    """The newest message of each topic the scenario reads, by handle: ``latest[ORB_ID.vehicle_status]`` is a
    ``VehicleStatus``."""

    def __init__(self) -> None:
        self._messages: dict[Topic, Any] = {}

    def __contains__(self, topic: Topic) -> bool:
        return topic in self._messages

    def __getitem__(self, topic: Topic[M]) -> M:
        return self._messages[topic]

    def __setitem__(self, topic: Topic[M], msg: M) -> None:
        self._messages[topic] = msg

    def get(self, topic: Topic[M]) -> M | None:
        return self._messages.get(topic)


class ScriptContext:
    """The script's handle on the stack; the scenario module drives it once per tick."""

    def __init__(
        self,
        publish: Callable[[Topic, Any], None],
        now_s: Callable[[], float],
        pids: Callable[[], dict[str, int]] = dict,
        swarm: SwarmRole | None = None,
    ) -> None:
        self._publish = publish
        self._now_s = now_s
        self._pids = pids
        self.swarm = swarm
        """The vehicle's place in a swarm flight (None: a flight of one vehicle)."""
        self.leader = LatestMessages()
        """The leader's topics (Swarm.peers) as this vehicle hears them now: each as published Swarm.peer_delay_s
        ago (a follower's only; missing before the first)."""
        self.end_flight: Callable[[], None] = _cannot_end
        self.latest = LatestMessages()
        self.series: dict[Topic, Series] = {}
        self.events: list[tuple[float, str]] = []
        self.tick_hooks: list[Callable[[], None]] = []
        self.state: dict[str, Any] = {}
        self.options: dict[str, str] = {}
        """The scenario's options as the profile chose them (see Scenario.options)."""
        self._acks: list[VehicleCommandAck] = []

    # -- time and waiting ------------------------------------------------------------------------------

    @property
    def now(self) -> float:
        """Simulated (or wall) time in seconds."""
        return self._now_s()

    def wait(self, seconds: float) -> Wait:
        end = self.now + seconds
        return lambda: self.now >= end - 1e-9

    def until(self, condition: Callable[[], bool], timeout: float, what: str) -> Wait:
        deadline = self.now + timeout

        def check() -> bool:
            if condition():
                return True
            if self.now > deadline:
                raise ScenarioError(f"timed out after {timeout:g} s waiting for {what}")
            return False

        return check

    def log(self, text: str) -> None:
        self.events.append((self.now, text))

    # -- data --------------------------------------------------------------------------------------------

    def record(self, topic: Topic, t: float, value: Any) -> None:
        self.series.setdefault(topic, Series()).add(t, value)

    def take_acks(self, acks: list[VehicleCommandAck]) -> None:
        self._acks.extend(acks)

    # -- processes -----------------------------------------------------------------------------------------

    def pid(self, module: str) -> int | None:
        """The process id of a running module of the stack (None while it is not running)."""
        return self._pids().get(module)

    def kill_stack(self) -> None:
        """End this vehicle at once, as a crash or a power loss would: its result is written as it stands, then its
        supervisor and every module are killed (SIGKILL), this one last."""
        self.log("killing every process of this vehicle")
        self.end_flight()
        supervisor = os.getppid()
        os.kill(supervisor, signal.SIGKILL)
        for pid in self._pids().values():
            if pid != os.getpid():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
        os.kill(os.getpid(), signal.SIGKILL)

    def kill(self, module: str) -> int:
        """SIGKILL a module of the stack, as a crash would end it; returns the pid it had."""
        pid = self.pid(module)
        if pid is None:
            raise ScenarioError(f"module {module} is not running")
        os.kill(pid, signal.SIGKILL)
        self.log(f"killed {module} (pid {pid})")
        return pid

    # -- commands ----------------------------------------------------------------------------------------

    def publish(self, topic: Topic[M], msg: M) -> None:
        self._publish(topic, msg)

    def command(self, command: int, timeout: float = 2.0, **params: float) -> Generator[Wait, None, VehicleCommandAck]:
        """Send a vehicle_command and wait for its acknowledgement; a refusal raises ScenarioError."""
        self._acks.clear()
        # Floats as the fields say (an int in a float field would go on the wire as a MessagePack int).
        floats = {name: float(value) for name, value in params.items()}
        # Addressed to whichever vehicle's bus it is on (a vehicle of a swarm is not MAVLink system 1).
        message = VehicleCommand(command=command, from_external=True, target_system=0, target_component=0, **floats)
        self.publish(ORB_ID.vehicle_command, message)
        label = command_label(command)
        yield self.until(lambda: any(a.command == command for a in self._acks), timeout, f"the ack of command {label}")
        ack = next(a for a in self._acks if a.command == command)
        if ack.result != VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED:
            result = RESULT_NAMES.get(ack.result, str(ack.result))
            raise ScenarioError(f"command {label} refused ({result}): {ack.reason or 'no reason given'}")
        self.log(f"command {label} accepted")
        return ack


def _cannot_end() -> None:
    raise ScenarioError("this flight's result cannot be written from here")


def degrees(values: list[float]) -> list[float]:
    return [math.degrees(v) for v in values]
