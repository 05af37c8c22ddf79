"""The time the ``mavlink`` module stamps what it publishes with.

The module runs on the wall clock and is no lockstep member: in lockstep it stamps its messages with the latest
simulated time it has seen on the bus (the ``timestamp`` of what it receives), so the modules that judge their
age (the commander's data-link and Offboard timeouts) see them as fresh on their own clock. Outside lockstep
every module's clock is the wall clock.
"""

from __future__ import annotations

from collections.abc import Callable


class StampClock:
    def __init__(self, lockstep: bool, wall_us: Callable[[], int]) -> None:
        self.lockstep = lockstep
        self.wall_us = wall_us
        self.latest_us = 0
        """The newest bus timestamp seen (0: none yet)."""

    def observe(self, timestamp_us: int) -> None:
        if timestamp_us > self.latest_us:
            self.latest_us = timestamp_us

    def now(self) -> int:
        """The stack's time now, as well as this module can tell (0 in lockstep before anything was seen)."""
        return self.latest_us if self.lockstep else self.wall_us()
