"""tests/support/machine.py: a marked test and another worker's tests never run at once, and neither waits forever."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from tests.support import machine
from tests.support.machine import Machine

STILL_WAITING_S = 0.5  # "nothing happens for a while": the waiting side has polled a few times


def in_thread(fn, *args) -> threading.Thread:
    thread = threading.Thread(target=fn, args=args, daemon=True)
    thread.start()
    return thread


def waits_until_released(waiting: threading.Thread, holder: Machine, why: str) -> None:
    time.sleep(STILL_WAITING_S)
    assert waiting.is_alive(), why
    holder.release()
    waiting.join(timeout=10)
    assert not waiting.is_alive()


def test_a_marked_test_waits_for_the_running_test_then_the_other_worker_waits_for_it(tmp_path: Path) -> None:
    marked_worker, other = Machine(tmp_path, "gw0", False), Machine(tmp_path, "gw1", False)
    other.before(marked=False)  # a long test of the other worker is running

    claim = in_thread(marked_worker.before, True)
    waits_until_released(claim, other, "the marked test started beside a running test")
    next_test = in_thread(other.before, False)
    waits_until_released(next_test, marked_worker, "the other worker started a test beside the marked one")
    other.release()
    assert list((tmp_path / "machine").iterdir()) == []


def test_the_first_test_of_a_worker_leaves_the_machine_to_marked_tests_about_to_start(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(machine, "FIRST_CLAIM_WAIT_S", 30.0)
    marked_worker, other = Machine(tmp_path, "gw0", True), Machine(tmp_path, "gw1", True)
    first_test = in_thread(other.before, False)  # started a moment before the marked one
    time.sleep(STILL_WAITING_S)
    marked_worker.before(marked=True)
    waits_until_released(first_test, marked_worker, "the first test started though the marked one claimed the machine")


def test_without_marked_tests_nothing_waits(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(machine, "FIRST_CLAIM_WAIT_S", 30.0)
    started = time.monotonic()
    one, other = Machine(tmp_path, "gw0", False), Machine(tmp_path, "gw1", False)
    one.before(marked=False)
    other.before(marked=False)
    assert time.monotonic() - started < 5.0


def test_a_claim_never_lasts_beyond_its_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A worker that died holding the machine (its file left behind) holds up the other one for a while only."""
    monkeypatch.setattr(machine, "WAIT_LIMIT_S", 1.0)
    Machine(tmp_path, "gw0", False).before(marked=True)
    other = Machine(tmp_path, "gw1", False)
    started = time.monotonic()
    other.before(marked=False)
    assert 1.0 <= time.monotonic() - started < 10.0
