"""Where runs live and how another terminal finds a running stack.

``$STACK_HOME`` (default ``~/.stack``) holds ``runs/<stamp>-<profile or scenario>-<name>/`` (per-module
logs and specs) and ``state/<vehicle>.<pid>.json``, one per running supervisor, with its pid, how it was started
(``kind``: ``up`` or ``fly``) and the bus endpoint, so ``stack status``, ``stack topic ...`` and
``stack down`` work from any terminal.

A stack is addressed by name: a ``stack up`` stack by its vehicle, a flight by ``<vehicle>-fly-<pid>``
(each flight is a stack of its own, on its own bus, beside any other). A command that names no stack
addresses the ``stack up`` stacks, or the flights when no ``stack up`` runs.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import psutil

UP = "up"
FLY = "fly"


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


def stack_name(state: dict[str, object]) -> str:
    """The name a running stack is addressed by."""
    vehicle = str(state["vehicle"])
    return flight_name(vehicle, int(state["pid"])) if state.get("kind") == FLY else vehicle


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
        pid = state.get("pid")
        if isinstance(pid, int) and psutil.pid_exists(pid):
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
    return [s for s in stacks if s.get("kind", UP) == UP] or stacks
