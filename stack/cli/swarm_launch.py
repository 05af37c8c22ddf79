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

import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType

import typer

from stack.runtime.world_clock import create_world, leave_world
from stack.supervisor.profile import Profile
from stack.supervisor.swarm import vehicle_copy, vehicle_names

WORLD_FILE = "world.clock"
RENDEZVOUS = re.compile(r"\[stack\] bus rendezvous (\S+),")
UP = re.compile(r"\[stack\] all \d+ modules up")


def check_swarm(profile: Profile, count: int) -> list[str]:
    """The vehicles' names, once every copy of the profile is known to be possible (a ValueError says why not)."""
    for index in range(1, count + 1):
        vehicle_copy(profile, index, count, join="tcp/127.0.0.1:1")
    return vehicle_names(profile, count)


def run_swarm(
    names: Sequence[str], args: Sequence[str], run_dir: Path, own: Callable[[str], list[str]] = lambda _: []
) -> int:
    """Start each vehicle's `stack ARGS` (``args``: ``up PROFILE ...`` or ``fly SCENARIO ...``, then ``own(name)``)
    on one world clock (its file in ``run_dir``), one after the other, and relay their lines until all have stopped;
    their worst exit code. A vehicle that does not come up stops them all."""
    world = run_dir / WORLD_FILE
    create_world(world, len(names))
    launched: list[_Vehicle] = []
    stopping: list[int] = []

    def stop(signum: int, _: FrameType | None) -> None:
        stopping.append(signum)
        for vehicle in launched:
            vehicle.signal(signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, stop)
    join = ""
    for index, name in enumerate(names, start=1):
        if stopping:
            break
        command = [sys.executable, "-m", "stack", *args, *own(name), "--swarm-vehicle", str(index)]
        command += ["--swarm-size", str(len(names)), "--swarm-world", str(world)]
        command += ("--swarm-join", join) if join else ()
        vehicle = _Vehicle(name, command)
        launched.append(vehicle)
        if not vehicle.wait_up():
            if not stopping:
                typer.echo(f"[swarm] {name} did not come up: stopping the swarm")
                stop(signal.SIGTERM, None)
            break
        join = join or vehicle.endpoint
    for slot in range(len(launched), len(names)):
        leave_world(world, slot)
    codes = _wait_all([v.child for v in launched], world)
    for vehicle, code in zip(launched, codes, strict=True):
        vehicle.relay.join()
        if code < 0:
            typer.echo(f"[swarm] {vehicle.name} was ended by {signal.Signals(-code).name}")
    return max(codes)


class _Vehicle:
    """One vehicle's `stack up`, its lines relayed, each starting with its name."""

    def __init__(self, name: str, command: list[str]) -> None:
        self.name = name
        self.endpoint = ""
        self.came_up = False
        self.up = threading.Event()
        self.child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
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


def _wait_all(children: list[subprocess.Popen[str]], world: Path) -> list[int]:
    """Each child's exit code once all have ended; as each ends, its vehicle leaves the world clock (the others
    go on without it)."""
    codes: dict[int, int] = {}
    while len(codes) < len(children):
        for slot, child in enumerate(children):
            if slot not in codes and (code := child.poll()) is not None:
                codes[slot] = code
                leave_world(world, slot)
        time.sleep(0.1)
    return [codes[slot] for slot in range(len(children))]
