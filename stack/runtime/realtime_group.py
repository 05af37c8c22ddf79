"""Modules of a real-time run sharing one process (a profile's ``process = "NAME"``), as PX4 runs the modules of a
work queue in one thread, one after another.

The process's thread runs every module: the timed ones as their timers come due (:class:`WallTimer`), and each
triggered one on every message of its trigger topic, first come first run. The modules share the process's
Zenoh session, which hands a message published by one of them to the others in memory, in the publishing
thread: a trigger published in the process (the attitude controller's rate setpoint, which runs the rate
controller) is run on as soon as the run that published it ends, and the messages of the control chain
between them never reach a socket or wake another thread, which is what a module in a process of its own
pays most of its CPU for. Messages from other processes wake the thread through one event that every
trigger subscription sets. The thread runs at the highest of the modules' work queues
(:mod:`stack.runtime.priority`).

A module stays a module: its own topics, parameters, heartbeat and status row. A module that fails, or asks to
stop the stack, ends the process with its error, and the supervisor restarts the process or stops the stack as
that module's entry says.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import TYPE_CHECKING

from stack.bus.node import wall_clock_us
from stack.runtime.wall_timer import WallTimer

if TYPE_CHECKING:
    from stack.runtime.runner import Runtime

IDLE_WAKE_S = 0.5
"""How long the thread waits at most with nothing due (a process of triggered modules only)."""


def serve_real_time_group(runtimes: Sequence[Runtime]) -> None:
    """Start every opened runtime, then run them on the wall clock until one fails or a signal stops the process."""
    arrival = threading.Event()
    start = wall_clock_us()
    timed: list[tuple[Runtime, WallTimer]] = []
    triggered: list[Runtime] = []
    for rt in runtimes:
        rt.start()
        period_us = rt.wall_period_us()
        if period_us is None:
            rt.trigger_subscriber.share_arrival(arrival)
            triggered.append(rt)
        else:
            timed.append((rt, WallTimer(period_us, start)))
    while True:
        ran = False
        now = wall_clock_us()
        for rt, timer in timed:
            if now >= timer.next_due:
                rt.wall_tick(timer.fire(now))
                ran = True
        for rt in triggered:
            item = rt.trigger_subscriber.poll()
            if item is not None:
                rt.wall_trigger(item)
                ran = True
        if ran:
            continue
        arrival.clear()
        if any(rt.trigger_subscriber.arrived for rt in triggered):
            continue
        next_due = min((timer.next_due for _, timer in timed), default=now + int(IDLE_WAKE_S * 1e6))
        delay_us = next_due - wall_clock_us()
        if delay_us > 0:
            arrival.wait(delay_us / 1e6)
