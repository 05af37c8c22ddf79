"""What every test runs with (tests/README.md): a STACK_HOME of its own, and, on pytest-xdist's workers, the
tests that share a stack kept together.

- Each test gets its own empty STACK_HOME, so a command that names no stack can only find the test's own, and
  nothing reaches the user's ``~/.stack``.
- The tests of a file that share a module-scoped fixture (a running stack) run on one worker, which starts it
  once (``--dist loadgroup`` groups them); the flights shared across files (``fly``, ``fly_here``) are flown
  once per run by whichever worker asks first (tests/support/once.py), so their tests spread freely.
- The flight tests are handed out first, the wall-clock ones that must not run beside each other (one worker
  flies them in turn, the ``heavy_wall_clock`` group) before all: the long ones start while the short ones fill
  the gaps, and no worker is left with a long flight at the end.
- Beside them the other tests yield: on a worker, every test outside the ``heavy_wall_clock`` group runs at
  niceness BESIDE_WALL_CLOCK_NICENESS (its stacks inherit it). The real-time stacks of that group take most of both
  cores themselves (three hosts' stacks: 70-100 %), and the parts of them that are not at real-time priority (the
  tools that watch them, the kernel's network work between the hosts) starved beside a flight of the other worker:
  the split vehicle's takeoff sank, its motor commands arrived late.
- Python caches its bytecode even where the environment asks it not to (``PYTHONDONTWRITEBYTECODE``, set on
  some CI machines): the suite starts thousands of processes that import the package from this checkout, and
  each would otherwise compile it from source again (about 0.3 s of CPU a process).
"""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

import pytest

SHARED_ACROSS_WORKERS = {"fly", "fly_here"}
HEAVY_WALL_CLOCK = "heavy_wall_clock"
BESIDE_WALL_CLOCK_NICENESS = 10


def pytest_configure(config: pytest.Config) -> None:
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    sys.dont_write_bytecode = False


@pytest.fixture(autouse=True)
def stack_home(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> Path:
    home = tmp_path_factory.mktemp("stack-home")
    monkeypatch.setenv("STACK_HOME", str(home))
    monkeypatch.delenv("STACK_ENDPOINT", raising=False)
    return home


def shares_a_fixture(item: pytest.Item) -> bool:
    """Whether the test uses a fixture of the test suite's own wider than a test (builtins have no base id)."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    return any(
        d.scope != "function" and d.baseid and name not in SHARED_ACROSS_WORKERS
        for name in info.names_closure
        for d in info.name2fixturedefs.get(name, ())
    )


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        # A test already in a group keeps it: a second mark would make a group of its own (xdist joins the names).
        if shares_a_fixture(item) and item.get_closest_marker("xdist_group") is None:
            item.add_marker(pytest.mark.xdist_group(item.nodeid.split("::")[0]))
    items.sort(key=lambda item: (not in_group(item, HEAVY_WALL_CLOCK), item.get_closest_marker("flight") is None))


def pytest_runtest_setup(item: pytest.Item) -> None:
    if "PYTEST_XDIST_WORKER" not in os.environ:
        return
    niceness = 0 if in_group(item, HEAVY_WALL_CLOCK) else BESIDE_WALL_CLOCK_NICENESS
    with contextlib.suppress(PermissionError):  # back to 0 needs the privilege; without it the worker stays nicer
        os.setpriority(os.PRIO_PROCESS, 0, niceness)


def in_group(item: pytest.Item, group: str) -> bool:
    return any(mark.args == (group,) for mark in item.iter_markers("xdist_group"))
