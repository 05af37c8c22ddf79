"""The loop of a real-time process group (stack/runtime/realtime_group.py) and the wall-clock timer, on stand-ins for
the runtimes: what runs when, with no bus."""

from __future__ import annotations

import collections
import threading
import time

import pytest

from stack.runtime.realtime_group import serve_real_time_group
from stack.runtime.wall_timer import WallTimer


class Done(Exception):
    """Ends a test's loop (a module's failure ends its process's loop the same way)."""


class Subscriber:
    """A trigger subscription: messages queued as Zenoh's thread (or a member publishing) queues them."""

    def __init__(self) -> None:
        self.arrived: collections.deque[str] = collections.deque()
        self.event = threading.Event()

    def share_arrival(self, event: threading.Event) -> None:
        self.event = event

    def put(self, item: str) -> None:
        self.arrived.append(item)
        self.event.set()

    def poll(self) -> str | None:
        return self.arrived.popleft() if self.arrived else None


class Member:
    """A module's runtime as the group's loop uses it; ``act`` is its run (``msg`` None on a timer tick)."""

    def __init__(self, name: str, period_us: int | None, act) -> None:
        self.name = name
        self.period_us = period_us
        self.act = act
        self.trigger_subscriber = Subscriber()
        self.started = False

    def start(self) -> None:
        self.started = True

    def wall_period_us(self) -> int | None:
        return self.period_us

    def wall_tick(self, now_us: int) -> None:
        self.act(None)

    def wall_trigger(self, item: str) -> None:
        self.act(item)


def test_a_trigger_published_in_the_process_runs_in_the_same_pass():
    """A timed source triggers a, whose run triggers b: each tick runs source, a, b, in that order, before the
    loop waits again; the members are listed in the opposite order, so it is the messages that order the runs."""
    events: list[str] = []

    def source(_: object) -> None:
        events.append("source")
        if events.count("source") == 5:
            raise Done
        a.trigger_subscriber.put("tick")

    def run_a(msg: object) -> None:
        events.append(f"a:{msg}")
        b.trigger_subscriber.put("from a")

    b = Member("b", None, lambda msg: events.append(f"b:{msg}"))
    a = Member("a", None, run_a)
    clock = Member("source", 20_000, source)
    with pytest.raises(Done):
        serve_real_time_group([b, a, clock])
    assert all(m.started for m in (a, b, clock))
    assert events == ["source", "a:tick", "b:from a"] * 4 + ["source"]


def test_a_message_from_outside_wakes_the_loop_before_its_next_timer():
    """With a timer due only in 60 s, a message queued by another thread (Zenoh's) is run at once."""
    ran: list[float] = []

    def triggered(msg: object) -> None:
        ran.append(time.monotonic())
        raise Done

    slow = Member("slow", 60_000_000, lambda msg: None)
    member = Member("member", None, triggered)
    sent_at: list[float] = []

    def send() -> None:
        time.sleep(0.2)  # the loop is waiting by then
        sent_at.append(time.monotonic())
        member.trigger_subscriber.put("outside")

    sender = threading.Thread(target=send)
    sender.start()
    with pytest.raises(Done):
        serve_real_time_group([slow, member])
    sender.join()
    assert ran[0] - sent_at[0] < 5.0  # woken by the message (the timer would have taken 60 s)


def test_timed_members_run_at_their_periods_side_by_side():
    counts = collections.Counter()
    began = time.monotonic()

    def tick(name: str):
        def run(_: object) -> None:
            counts[name] += 1
            if counts["fast"] == 41:
                raise Done

        return run

    with pytest.raises(Done):
        serve_real_time_group([Member("fast", 10_000, tick("fast")), Member("slow", 40_000, tick("slow"))])
    elapsed = time.monotonic() - began
    assert elapsed >= 0.4  # 40 periods of 10 ms after the first tick: never early
    # The slow timer ran once per four of the fast one's (a machine that stalls the loop skips ticks: fewer).
    assert 1 <= counts["slow"] <= 11


def test_a_timer_that_comes_late_skips_the_ticks_it_missed():
    timer = WallTimer(10_000, 1_000_000)
    assert timer.fire(1_000_000) == 1_000_000 and timer.next_due == 1_010_000
    assert timer.fire(1_012_000) == 1_012_000 and timer.next_due == 1_020_000  # late within a period: kept
    timer.fire(1_095_000)  # 7 periods late
    assert timer.next_due == 1_105_000  # the next a period from now, not 7 at once
