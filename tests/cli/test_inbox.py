"""The bounded queue behind `stack topic echo`: oldest dropped and counted, never more than its capacity."""

import threading

import pytest

from stack.cli.inbox import Inbox


def test_the_oldest_are_dropped_and_counted():
    inbox: Inbox[int] = Inbox(3)
    for i in range(10):
        inbox.put(i)
    assert inbox.dropped == 7
    assert [inbox.get(0.0) for _ in range(4)] == [7, 8, 9, None]


def test_a_reader_waits_for_a_writer():
    inbox: Inbox[str] = Inbox(1)
    threading.Timer(0.05, inbox.put, ("late",)).start()
    assert inbox.get(30.0) == "late" and inbox.dropped == 0


def test_capacity_must_be_positive():
    with pytest.raises(ValueError, match="at least 1"):
        Inbox(0)
