"""Where runs live and how another terminal finds a running stack.

``$STACK_HOME`` (default ``~/.stack``) holds ``runs/<stamp>-<profile>/`` (per-module logs and specs)
and ``state/<vehicle>.json``, written by ``stack up`` with the supervisor's pid and the bus
endpoint, so ``stack status``, ``stack topic ...`` and ``stack down`` work from any terminal.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import psutil


def stack_home() -> Path:
    return Path(os.environ.get("STACK_HOME", Path.home() / ".stack"))


def new_run_dir(profile: str, vehicle: str) -> Path:
    base = stack_home() / "runs"
    stamp = time.strftime("%Y%m%d-%H%M%S")
    path = base / f"{stamp}-{profile}-{vehicle}"
    n = 1
    while path.exists():
        n += 1
        path = base / f"{stamp}-{profile}-{vehicle}-{n}"
    path.mkdir(parents=True)
    return path


def state_path(vehicle: str) -> Path:
    return stack_home() / "state" / f"{vehicle}.json"


def write_state(vehicle: str, state: dict[str, object]) -> None:
    path = state_path(vehicle)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(state, indent=2))
    tmp.replace(path)


def remove_state(vehicle: str, pid: int) -> None:
    path = state_path(vehicle)
    try:
        if json.loads(path.read_text()).get("pid") == pid:
            path.unlink()
    except (FileNotFoundError, json.JSONDecodeError):
        pass


def running_stacks() -> list[dict[str, object]]:
    """States of stacks whose supervisor is still alive (stale files are ignored)."""
    found = []
    for path in sorted((stack_home() / "state").glob("*.json")):
        try:
            state = json.loads(path.read_text())
        except (json.JSONDecodeError, OSError):
            continue
        pid = state.get("pid")
        if isinstance(pid, int) and psutil.pid_exists(pid):
            found.append(state)
    return found
