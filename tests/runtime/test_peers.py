"""The delay rule of a peer input (stack.runtime.peers.PeerStream): what a vehicle hears of another, and when."""

from __future__ import annotations

import pytest

from stack.runtime.peers import PeerStream


def test_the_message_due_is_the_newest_published_at_least_the_delay_ago() -> None:
    stream = PeerStream(100_000)
    assert stream.at(1_000_000) is None
    for t in range(0, 400_001, 20_000):
        stream.add(t, t)
    assert stream.at(150_000) == 40_000
    assert stream.at(320_000) == 220_000
    assert stream.at(600_000) == 400_000


def test_everything_due_has_arrived_once_a_later_message_has() -> None:
    stream = PeerStream(100_000)
    assert stream.complete(5_000_000)  # nothing heard yet: nothing to wait for
    stream.add(1_000_000, "a")
    assert stream.complete(1_099_999)
    assert not stream.complete(1_100_000)
    stream.add(1_020_000, "b")
    assert stream.complete(1_100_000) and stream.at(1_100_000) == "a"


def test_a_delay_must_be_positive() -> None:
    with pytest.raises(ValueError):
        PeerStream(0)


def test_a_message_stamped_far_ahead_never_holds_back_the_others() -> None:
    stream = PeerStream(100_000)
    stream.add(0, "first")
    stream.add(10**15, "forged")
    stream.add(20_000, "second")
    assert stream.at(120_000) == "second"
