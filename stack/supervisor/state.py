"""Where runs live and how another terminal finds a running stack.

``$STACK_HOME`` (default ``~/.stack``) holds ``runs/<stamp>-<profile or scenario>-<name>/`` (per-module
logs and specs) and ``state/<vehicle>.<pid>.json``, one per running supervisor, with its pid (and the
process's start time), how it was started (``kind``: ``up``, ``fly`` or ``replay``) and the bus endpoint,
so ``stack status``, ``stack topic ...`` and ``stack down`` work from any terminal. A state whose process
is gone, a zombie, or a pid since reused by another program (a supervisor killed by SIGKILL cannot clean
up) is removed when read.

A stack is addressed by name: a ``stack up`` stack by its vehicle (as is a ``stack router``, a host's share of a
vehicle spread over machines that runs no module), a flight by ``<vehicle>-fly-<pid>``, a
replay by ``<vehicle>-replay-<pid>`` (each a stack of its own, on its own bus, beside any other). A command
that names no stack addresses the ``stack up`` stacks, or the others when no ``stack up`` runs.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import psutil

UP = "up"
FLY = "fly"
REPLAY = "replay"
ROUTER = "router"


def stack_home() -> Path:
    return Path(os.environ.get("STACK_HOME", Path.home() / ".stack"))


def new_run_dir(label: str, name: str) -> Path:
    """A new directory ``runs/<stamp>-<label>-<name>[-n]`` for the stack of that name; ``mkdir`` claims it,
    so stacks started in the same second, in any processes, never share one."""
    base = stack_home() / "runs"
    base.mkdir(parents=True, exist_ok=True)
    stem = f"{time.strftime('%Y%m%d-%H%M%S')}-{label}-{name}"
    path, n = base / stem, 1
    while True:
        try:
            path.mkdir()
            return path
        except FileExistsError:
            n += 1
            path = base / f"{stem}-{n}"


def flight_name(vehicle: str, pid: int) -> str:
    return f"{vehicle}-{FLY}-{pid}"


def replay_name(vehicle: str, pid: int) -> str:
    return f"{vehicle}-{REPLAY}-{pid}"


def stack_name(state: dict[str, object]) -> str:
    """The name a running stack is addressed by."""
    vehicle, kind = str(state["vehicle"]), state.get("kind", UP)
    return vehicle if kind in (UP, ROUTER) else f"{vehicle}-{kind}-{state['pid']}"


def start_ticks(pid: int) -> int:
    """When process ``pid`` started, in clock ticks since boot (``/proc/<pid>/stat`` field 22, proc(5)).

    Not psutil's ``create_time()``: that adds the boot time, which Linux derives from the wall clock and reports
    in whole seconds, so a clock adjustment moves it by a second and a live supervisor would look like another
    program that took its pid. Raises OSError if there is no such process."""
    with open(f"/proc/{pid}/stat", "rb") as f:
        stat = f.read()
    return int(stat[stat.rindex(b")") + 2 :].split()[19])


def process_identity() -> dict[str, object]:
    """This process's pid and start time, for a state record (see :func:`is_alive`)."""
    pid = os.getpid()
    return {"pid": pid, "pid_started": start_ticks(pid)}


def is_alive(state: dict[str, object]) -> bool:
    """Whether the process that wrote the state still runs: not gone, not a zombie, and (when the state
    says when it started) not another program that got the pid since."""
    pid = state.get("pid")
    if not isinstance(pid, int):
        return False
    try:
        if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
            return False
        started = state.get("pid_started")
        return not isinstance(started, int) or start_ticks(pid) == started
    except (psutil.Error, OSError, ValueError, IndexError):
        return False


def state_path(vehicle: str, pid: int) -> Path:
    return stack_home() / "state" / f"{vehicle}.{pid}.json"


def write_state(vehicle: str, state: dict[str, object]) -> None:
    path = state_path(vehicle, int(state["pid"]))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(state, indent=2))
    tmp.replace(path)


def remove_state(vehicle: str, pid: int) -> None:
    state_path(vehicle, pid).unlink(missing_ok=True)


def running_stacks() -> list[dict[str, object]]:
    """States of stacks whose supervisor is still alive; those left by a killed supervisor are removed."""
    found = []
    for path in sorted((stack_home() / "state").glob("*.json")):
        try:
            state = json.loads(path.read_text())
        except (json.JSONDecodeError, OSError):
            continue
        if is_alive(state):
            found.append(state)
        else:
            path.unlink(missing_ok=True)
    return found


def addressed_stacks(name: str | None) -> list[dict[str, object]]:
    """The running stacks a command addresses: the one of that name, else those of ``stack up``, else the
    flights (so a running flight never makes an unnamed command ambiguous while a ``stack up`` runs)."""
    stacks = running_stacks()
    if name is not None:
        return [s for s in stacks if stack_name(s) == name]
    return [s for s in stacks if s.get("kind", UP) in (UP, ROUTER)] or stacks
