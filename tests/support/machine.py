"""The machine to itself: a test marked ``machine_to_itself`` runs while no other worker runs a test.

Three hosts' real-time stacks emulated on a two-core machine take what three machines' CPUs would give them: their
control loops at real-time priority take about 1.3 cores, and the routers and the kernel's network work between the
hosts (at normal priority) get the rest. A flight of the other worker beside them, even at a high niceness, made
their messages late by 50-350 ms now and then, and a vehicle's rate loop closed over such a link tumbles at liftoff.
So while such a test runs, the other worker waits between its tests (tests/conftest.py applies this rule).

The workers agree through files in the run's shared temporary directory (the parent of each worker's own):

- a worker about to run a test writes ``busy-WORKER``, then looks for ``alone``: if it is there, it takes ``busy``
  back and waits until ``alone`` is gone;
- a worker about to run a marked test writes ``alone``, then waits until no other worker's ``busy`` file is left
  (a test already running ends first);
- each removes its file when the test has ended, however it ended.

Each writes its own file before it looks at the other's, so of two that start at once at least one sees the other,
and only the plain test ever steps back: they never both run, and never both wait. The marked tests go first in
their worker's queue (tests/conftest.py sorts them first), and a worker's first plain test waits a few seconds for
them to claim the machine, so that the other worker does not start a long flight just before them. They must all
be in one xdist group (one worker flies them in turn): two marked tests on two workers would wait for each other.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

MARK = "machine_to_itself"
FIRST_CLAIM_WAIT_S = 10.0
"""How long a worker's first plain test waits for a marked test of another worker to claim the machine."""
WAIT_LIMIT_S = 900.0
"""The longest wait for the machine (the marked tests' own timeouts are shorter): then the test runs anyway."""
POLL_S = 0.2


class Machine:
    """One worker's side of the agreement, in ``shared`` (a directory every worker of the run sees)."""

    def __init__(self, shared: Path, worker: str, marked_pending: bool) -> None:
        self.directory = shared / "machine"
        self.directory.mkdir(exist_ok=True)
        self.worker = worker
        self._first = marked_pending
        self._held: Path | None = None

    def _present(self, name: str) -> bool:
        return (self.directory / name).exists()

    def _others_busy(self) -> bool:
        return any(p.name != f"busy-{self.worker}" for p in self.directory.glob("busy-*"))

    def _hold(self, name: str) -> Path:
        path = self.directory / name
        path.touch()
        self._held = path
        return path

    def release(self) -> None:
        if self._held is not None:
            self._held.unlink(missing_ok=True)
            self._held = None

    def before(self, marked: bool) -> None:
        """Before a test: claim the machine (``marked``) or a share of it."""
        deadline = time.monotonic() + WAIT_LIMIT_S
        if marked:
            self._hold("alone")
            while self._others_busy() and time.monotonic() < deadline:
                time.sleep(POLL_S)
            return
        if self._first:
            self._first = False
            claim_by = time.monotonic() + FIRST_CLAIM_WAIT_S
            while not self._present("alone") and time.monotonic() < claim_by:
                time.sleep(POLL_S)
        while True:
            self._hold(f"busy-{self.worker}")
            if not self._present("alone") or time.monotonic() >= deadline:
                return
            self.release()
            while self._present("alone") and time.monotonic() < deadline:
                time.sleep(POLL_S)


def marked(item: pytest.Item) -> bool:
    return item.get_closest_marker(MARK) is not None
