"""A boolean state that changes only after the requested value has held for a while.

Follows PX4 ``src/lib/hysteresis/hysteresis.cpp`` (``systemlib::Hysteresis``): each direction of change
(false → true, true → false) has its own hold time; a request that flips back before its time has
elapsed is forgotten. Times are integer microseconds.
"""

from __future__ import annotations


class Hysteresis:
    __slots__ = ("_requested", "_requested_since_us", "_time_from_false_us", "_time_from_true_us", "state")

    def __init__(self, initial: bool) -> None:
        self.state = initial
        self._requested = initial
        self._requested_since_us = 0
        self._time_from_true_us = 0
        self._time_from_false_us = 0

    def set_hysteresis_time_from(self, from_state: bool, time_us: int) -> None:
        """Hold time before leaving ``from_state`` (PX4 ``set_hysteresis_time_from``)."""
        if from_state:
            self._time_from_true_us = time_us
        else:
            self._time_from_false_us = time_us

    def set_state_and_update(self, new_state: bool, now_us: int) -> bool:
        """Request ``new_state`` at ``now_us`` and return the (possibly unchanged) state."""
        if new_state != self.state:
            if new_state != self._requested:
                self._requested = new_state
                self._requested_since_us = now_us
        else:
            self._requested = self.state
        return self.update(now_us)

    def update(self, now_us: int) -> bool:
        if self._requested != self.state:
            hold_us = self._time_from_true_us if self.state else self._time_from_false_us
            if now_us - self._requested_since_us >= hold_us:
                self.state = self._requested
        return self.state

    def force(self, state: bool) -> None:
        """Set the state at once and drop any pending request."""
        self.state = state
        self._requested = state
