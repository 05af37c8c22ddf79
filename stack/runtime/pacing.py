"""Simulated or recorded time held to the wall clock at a speed factor.

A lockstep stack (``stack up --speed``, as PX4 SITL's ``PX4_SIM_SPEED_FACTOR`` paces its lockstep) and a
replay (``stack log replay --speed``) both let time run as fast as ``speed`` × the wall clock allows and no
faster: each step or message waits until its time, counted from the first, divided by the speed, has passed
on the wall clock. Speed 0 is as fast as possible.

A run that falls behind by more than MAX_LAG_S (the lockstep waited for a restarted module, a slow
subscriber held a replay) carries on from where it is at the same speed: it does not race to catch up,
which a vehicle watched in QGroundControl would show as a burst of fast motion.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

MAX_LAG_S = 0.5
MIN_SLEEP_S = 0.0005
MAX_SPEED = 0.0
"""The speed that means "as fast as possible"."""
SPEED_ENV = "STACK_SPEED"
"""The environment variable that sets ``stack up``'s speed when ``--speed`` is not given."""


def parse_speed(text: str) -> float:
    """``max`` (or 0) or a factor > 0 (``1``, ``2``, ``0.5``) as a speed (MAX_SPEED for ``max``); else ValueError."""
    if text.strip().lower() in ("max", "0"):
        return MAX_SPEED
    try:
        speed = float(text)
    except ValueError:
        speed = math.nan
    if not (math.isfinite(speed) and speed > 0.0):
        raise ValueError(f"speed must be a factor > 0 of the wall clock (1: real time) or max, not {text!r}")
    return speed


def describe_speed(speed: float) -> str:
    return "as fast as possible" if speed == MAX_SPEED else f"at {speed:g}x real time"


class Pacer:
    """When each step or message of time ``t_us`` is due (``restart`` begins a new pass, as ``--loop`` does).

    Times never go backwards: one stamped earlier than its predecessor is due at once.
    """

    __slots__ = ("_clock", "_first_us", "_last_us", "_sleep", "_start_s", "behind", "speed")

    def __init__(
        self,
        speed: float,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if not (math.isfinite(speed) and speed >= 0.0):
            raise ValueError(f"speed must be >= 0 (0: as fast as possible), not {speed}")
        self.speed = speed
        self._clock = clock
        self._sleep = sleep
        self._first_us: int | None = None
        self._last_us = 0
        self._start_s = 0.0
        self.behind = 0
        """How many times the run fell more than MAX_LAG_S behind and carried on from there."""

    def restart(self) -> None:
        self._first_us = None

    def delay_s(self, t_us: int) -> float:
        """Seconds to wait before time ``t_us`` (0 if it is due)."""
        if self.speed == MAX_SPEED:
            return 0.0
        now = self._clock()
        if self._first_us is None:
            self._first_us = self._last_us = t_us
            self._start_s = now
            return 0.0
        if t_us > self._last_us:
            self._last_us = t_us
        due = self._start_s + (self._last_us - self._first_us) / 1e6 / self.speed
        if now - due > MAX_LAG_S:
            self._first_us, self._start_s = self._last_us, now
            self.behind += 1
            return 0.0
        return max(0.0, due - now)

    def wait(self, t_us: int) -> None:
        """Sleep until time ``t_us`` is due."""
        delay = self.delay_s(t_us)
        if delay > MIN_SLEEP_S:
            self._sleep(delay)
