"""The lockstep start-up timeout counts from the supervisor's complete roster, not from when a module began waiting."""

from __future__ import annotations

import pytest

from stack.runtime import start_deadline
from stack.runtime.start_deadline import StartDeadline


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> Clock:
    c = Clock()
    monkeypatch.setattr(start_deadline.time, "monotonic", c)
    return c


def test_no_timeout_while_the_supervisor_is_still_starting_modules(clock: Clock) -> None:
    deadline = StartDeadline(60.0)
    for _ in range(10):
        clock.now += 100.0
        assert not deadline.passed(roster_complete=False)


def test_the_timeout_counts_from_the_first_complete_roster(clock: Clock) -> None:
    deadline = StartDeadline(60.0)
    clock.now += 500.0
    assert not deadline.passed(roster_complete=False)
    assert not deadline.passed(roster_complete=True)
    clock.now += 59.0
    assert not deadline.passed(roster_complete=True)
    clock.now += 2.0
    assert deadline.passed(roster_complete=True)


def test_a_roster_seen_once_keeps_the_clock_running(clock: Clock) -> None:
    deadline = StartDeadline(60.0)
    assert not deadline.passed(roster_complete=True)
    clock.now += 61.0
    assert deadline.passed(roster_complete=False)
