"""The world clock kept over the bus (stack.runtime.bus_world_clock), for a swarm spread over machines: the rule of
the world file, with a vehicle's liveliness token saying whether it takes part."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest
import zenoh

from stack.bus.config import BusConfig
from stack.runtime.bus_world_clock import BusWorldClock
from stack.runtime.world_clock import SLACK_US

P = 4000
NAMES = ["v1", "v2"]


@pytest.fixture
def session() -> Iterator[zenoh.Session]:
    s = zenoh.open(BusConfig().zenoh_config("world-clock-test"))
    yield s
    s.close()


def waits(clock: BusWorldClock, t_us: int) -> threading.Thread:
    thread = threading.Thread(target=clock.wait, args=(t_us, P), daemon=True)
    thread.start()
    return thread


def test_the_slack_the_catching_up_and_a_vehicle_that_leaves(session: zenoh.Session) -> None:
    a, b = BusWorldClock(session, 0, NAMES), BusWorldClock(session, 1, NAMES)
    ahead = SLACK_US // P
    try:
        for k in range(1, ahead + 1):
            a.wait(k * P, P)
            a.done(k * P)
        blocked = waits(a, (ahead + 1) * P)
        blocked.join(0.5)
        assert blocked.is_alive(), "v1 ran more than the slack ahead of v2"
        for k in range(1, ahead + 1):
            b.wait(k * P, P)
            b.done(k * P)
        blocked.join(5.0)
        assert not blocked.is_alive()
        blocked = waits(a, 10 * ahead * P)
        blocked.join(0.5)
        assert blocked.is_alive()
        b.close()  # its token goes: v1 waits for it no more
        blocked.join(5.0)
        assert not blocked.is_alive()
    finally:
        a.close()


def test_a_vehicle_not_yet_started_is_waited_for(session: zenoh.Session) -> None:
    a = BusWorldClock(session, 0, NAMES)
    try:
        blocked = waits(a, SLACK_US + P)
        blocked.join(0.5)
        assert blocked.is_alive()
        b = BusWorldClock(session, 1, NAMES)
        b.done(SLACK_US)
        blocked.join(5.0)
        assert not blocked.is_alive()
        b.close()
    finally:
        a.close()
