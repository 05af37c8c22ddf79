"""A module's timer on the wall clock (real time): due every period from its start, as PX4's
``ScheduledWorkItem::ScheduleOnInterval``; a tick that comes late skips the ticks it missed instead of running
them in a burst."""

from __future__ import annotations


class WallTimer:
    def __init__(self, period_us: int, start_us: int) -> None:
        self.period_us = period_us
        self.next_due = start_us

    def fire(self, now_us: int) -> int:
        """Take the tick due (at ``now_us``, on or after it is due) and schedule the next; returns ``now_us``."""
        self.next_due += self.period_us
        if self.next_due < now_us:
            self.next_due = now_us + self.period_us
        return now_us
