"""``stack up PROFILE --vehicles N``: N copies of the profile's vehicle on one bus (stack.supervisor.swarm).

Each vehicle is a `stack up` of its own (its supervisor, router, run directory and state, so `stack status
--vehicle v2` and `stack down --vehicle v2` reach it), started by this process: the first, then the others
joining its router once it gives its endpoint, all on one world clock in lockstep (stack.runtime.world_clock).
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
from collections.abc import Sequence
from pathlib import Path
from types import FrameType

import typer

from stack.runtime.world_clock import create_world, leave_world
from stack.supervisor.profile import Profile
from stack.supervisor.swarm import vehicle_copy, vehicle_names

WORLD_FILE = "world.clock"
RENDEZVOUS = re.compile(r"\[stack\] bus rendezvous (\S+),")


def check_swarm(profile: Profile, count: int) -> list[str]:
    """The vehicles' names, once every copy of the profile is known to be possible (a ValueError says why not)."""
    for index in range(1, count + 1):
        vehicle_copy(profile, index, count, join="tcp/127.0.0.1:1")
    return vehicle_names(profile, count)


def run_swarm(names: Sequence[str], up_args: Sequence[str], run_dir: Path) -> int:
    """Start each vehicle's `stack up UP_ARGS` on one world clock (its file in ``run_dir``) and relay its lines until
    all have stopped; their worst exit code."""
    world = run_dir / WORLD_FILE
    create_world(world, len(names))
    children: list[subprocess.Popen[str]] = []
    relays: list[threading.Thread] = []
    joined = threading.Event()
    endpoint: list[str] = []

    def start(index: int, join: str) -> None:
        command = [sys.executable, "-m", "stack", "up", *up_args, "--swarm-vehicle", str(index)]
        command += ["--swarm-size", str(len(names)), "--swarm-world", str(world)]
        command += ("--swarm-join", join) if join else ()
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        children.append(child)
        relay = threading.Thread(target=_relay, args=(child, names[index - 1], endpoint, joined), daemon=True)
        relay.start()
        relays.append(relay)

    stopping: list[int] = []

    def stop(signum: int, _: FrameType | None) -> None:
        stopping.append(signum)
        joined.set()
        for child in children:
            if child.poll() is None:
                child.send_signal(signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, stop)
    start(1, "")
    while not joined.wait(0.2):
        if children[0].poll() is not None:
            joined.set()
    if endpoint and not stopping:
        for index in range(2, len(names) + 1):
            start(index, endpoint[0])
    codes = _wait_all(children, world)
    for relay in relays:
        relay.join()
    return max(codes)


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


def _relay(child: subprocess.Popen[str], name: str, endpoint: list[str], joined: threading.Event) -> None:
    assert child.stdout is not None
    for line in child.stdout:
        if not endpoint and (m := RENDEZVOUS.search(line)) is not None:
            endpoint.append(m.group(1))
            joined.set()
        typer.echo(f"{name}: {line.rstrip()}")
