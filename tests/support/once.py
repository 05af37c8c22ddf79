"""Work done once per test run, whichever pytest-xdist worker asks first: a flight several tests look at.

Each worker is a process of its own, so a session fixture alone would fly a flight once per worker. The first
worker to ask for a key does the work under an exclusive lock on a file in the run's shared temporary directory
(the parent of every worker's ``basetemp``) and leaves the result there as JSON; a worker asking meanwhile waits
for the lock, then reads it.
"""

from __future__ import annotations

import fcntl
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest


def shared_dir(factory: pytest.TempPathFactory) -> Path:
    """A directory every worker of this test run shares (the run's own with no workers)."""
    base = factory.getbasetemp()
    root = base.parent if re.fullmatch(r"popen-gw\d+", base.name) else base
    shared = root / "shared"
    shared.mkdir(exist_ok=True)
    return shared


def key_dir(factory: pytest.TempPathFactory, key: str) -> Path:
    """The directory of ``key``'s work, shared by every worker."""
    return shared_dir(factory) / re.sub(r"[^A-Za-z0-9_.-]+", "-", key)


def once(factory: pytest.TempPathFactory, key: str, work: Callable[[Path], Any]) -> Any:
    """``work(key_dir(factory, key))``'s JSON-able result, computed by the first worker to ask for ``key``."""
    directory = key_dir(factory, key)
    done = directory / "result.json"
    with open(directory.with_name(directory.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            directory.mkdir(exist_ok=True)
            result = work(directory)
            done.write_text(json.dumps(result))
        return json.loads(done.read_text())
