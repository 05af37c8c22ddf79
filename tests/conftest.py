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
- Python caches its bytecode even where the environment asks it not to (``PYTHONDONTWRITEBYTECODE``, set on
  some CI machines): the suite starts thousands of processes that import the package from this checkout, and
  each would otherwise compile it from source again (about 0.3 s of CPU a process).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

SHARED_ACROSS_WORKERS = {"fly", "fly_here"}
HEAVY_WALL_CLOCK = "heavy_wall_clock"


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
        if shares_a_fixture(item):
            item.add_marker(pytest.mark.xdist_group(item.nodeid.split("::")[0]))
    items.sort(key=lambda item: (not in_group(item, HEAVY_WALL_CLOCK), item.get_closest_marker("flight") is None))


def in_group(item: pytest.Item, group: str) -> bool:
    return any(mark.args == (group,) for mark in item.iter_markers("xdist_group"))
