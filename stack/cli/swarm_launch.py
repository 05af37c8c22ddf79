"""``stack up PROFILE --vehicles N`` and ``stack fly SCENARIO --vehicles N``: N copies of the profile's vehicle on one
bus (stack.supervisor.swarm).

Each vehicle is a `stack up` (or `stack fly`) of its own (its supervisor, router, run directory and state, so `stack
status --vehicle v2` and `stack down --vehicle v2` reach it), started by this process one after the other, each once the
one before is up (on a small machine, dozens of module processes starting at once would miss their start-up
deadlines), the others joining the first one's router, all on one world clock in lockstep
(stack.runtime.world_clock).
Their lines are relayed here, each starting with its vehicle. Ctrl-C or SIGTERM stops them all; the exit code is
the worst of theirs.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType
from typing import Any

import typer

from stack.runtime.orphan import ask_kernel_for_sigterm
from stack.runtime.world_clock import BUS_WORLD, create_world, leave_world
from stack.supervisor.profile import Profile
from stack.supervisor.swarm import vehicle_copy, vehicle_names

WORLD_FILE = "world.clock"
LAUNCHER_ENV = "STACK_SWARM_LAUNCHER"
"""The launcher's pid, in each vehicle's environment: a vehicle stops when its launcher dies, as a module does when
its supervisor dies (stack.runtime.orphan), so a launcher killed outright (SIGKILL) leaves no vehicle behind."""
RENDEZVOUS = re.compile(r"\[stack\] bus rendezvous (\S+),")
UP = re.compile(r"\[stack\] all \d+ modules up")


def check_swarm(profile: Profile, count: int) -> list[str]:
    """The vehicles' names, once every copy of the profile is known to be possible (a ValueError says why not)."""
    for index in range(1, count + 1):
        vehicle_copy(profile, index, count, join="tcp/127.0.0.1:1")
    return vehicle_names(profile, count)


def vehicle_of_swarm(
    profile: Profile, index: int, size: int, join: str, world: str
) -> tuple[Profile, list[str], dict[str, Any]]:
    """What a launcher's child (``--swarm-vehicle INDEX``...) runs: vehicle ``index`` of the swarm, the vehicles'
    names, and its world clock's options (stack.supervisor.supervisor.UpOptions); one clear line if impossible. A
    vehicle started by a launcher (LAUNCHER_ENV) is stopped (SIGTERM) by the kernel when the launcher dies."""
    launcher = os.environ.pop(LAUNCHER_ENV, "")
    if launcher.isdigit():
        ask_kernel_for_sigterm()
        if os.getppid() != int(launcher):
            typer.echo("error: the swarm's launcher is gone", err=True)
            raise typer.Exit(1)
    try:
        names = vehicle_names(profile, size)
        vehicle = vehicle_copy(profile, index, size, join)
    except ValueError as e:
        typer.echo(f"error: {e}", err=True)
        raise typer.Exit(2) from None
    return vehicle, names, {"world": world, "world_slot": index - 1, "world_vehicles": tuple(names)}


def run_swarm(
    names: Sequence[str],
    args: Sequence[str],
    run_dir: Path,
    own: Callable[[str], list[str]] = lambda _: [],
    here: Sequence[str] | None = None,
    hub: str = "",
) -> int:
    """Start each vehicle's `stack ARGS` (``args``: ``up PROFILE ...`` or ``fly SCENARIO ...``, then ``own(name)``)
    on one world clock, one after the other, and relay their lines until all have stopped; their worst exit code. A
    vehicle that does not come up stops them all. The world clock is a file in ``run_dir``; with ``here`` (the
    vehicles of ``names`` this machine runs, the others running on other machines) it is kept over the bus, and
    every vehicle joins the bus at ``hub``."""
    local = [(index, name) for index, name in enumerate(names, start=1) if here is None or name in here]
    world = run_dir / WORLD_FILE if here is None else None
    if world is not None:
        create_world(world, len(names))
    launched: list[_Vehicle] = []
    stopping: list[int] = []

    def stop(signum: int, _: FrameType | None) -> None:
        stopping.append(signum)
        for vehicle in launched:
            vehicle.signal(signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, stop)
    join = hub
    for index, name in local:
        if stopping:
            break
        command = [sys.executable, "-m", "stack", *args, *own(name), "--swarm-vehicle", str(index)]
        command += ["--swarm-size", str(len(names)), "--swarm-world", str(world) if world is not None else BUS_WORLD]
        command += ("--swarm-join", join) if join else ()
        vehicle = _Vehicle(name, command, index - 1)
        launched.append(vehicle)
        if not vehicle.wait_up():
            if not stopping:
                typer.echo(f"[swarm] {name} did not come up: stopping the swarm")
                stop(signal.SIGTERM, None)
            break
        join = join or vehicle.endpoint
    if world is not None:
        for index, _ in local[len(launched) :]:
            leave_world(world, index - 1)
    codes = _wait_all(launched, world)
    for vehicle, code in zip(launched, codes, strict=True):
        vehicle.relay.join()
        if code < 0:
            typer.echo(f"[swarm] {vehicle.name} was ended by {signal.Signals(-code).name}")
    return max(codes, default=0)


class _Vehicle:
    """One vehicle's `stack up`, its lines relayed, each starting with its name."""

    def __init__(self, name: str, command: list[str], slot: int) -> None:
        self.name = name
        self.slot = slot
        self.endpoint = ""
        self.came_up = False
        self.up = threading.Event()
        self.child = subprocess.Popen(
            command,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env={**os.environ, LAUNCHER_ENV: str(os.getpid())},
        )
        self.relay = threading.Thread(target=self._relay, daemon=True)
        self.relay.start()

    def _relay(self) -> None:
        assert self.child.stdout is not None
        for line in self.child.stdout:
            if not self.endpoint and (m := RENDEZVOUS.search(line)) is not None:
                self.endpoint = m.group(1)
            if UP.search(line):
                self.came_up = True
                self.up.set()
            typer.echo(f"{self.name}: {line.rstrip()}")
        self.up.set()

    def wait_up(self) -> bool:
        """Whether it came up (False: it ended first)."""
        self.up.wait()
        return self.came_up

    def signal(self, signum: int) -> None:
        if self.child.poll() is None:
            self.child.send_signal(signum)


def _wait_all(vehicles: list[_Vehicle], world: Path | None) -> list[int]:
    """Each vehicle's exit code once all have ended; as each ends, it leaves the world clock's file (the others go
    on without it; over the bus its token goes with it)."""
    codes: dict[int, int] = {}
    while len(codes) < len(vehicles):
        for i, vehicle in enumerate(vehicles):
            if i not in codes and (code := vehicle.child.poll()) is not None:
                codes[i] = code
                if world is not None:
                    leave_world(world, vehicle.slot)
        time.sleep(0.1)
    return [codes[i] for i in range(len(vehicles))]
