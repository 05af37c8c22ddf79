"""How fast a parameter list goes out on a link, I/O-free.

PX4's mavlink module sends the parameter list paced by the link's rate (``MavlinkParametersManager::send``,
``src/modules/mavlink/mavlink_parameters.cpp``): one PARAM_VALUE per pass, more when the link has room. Here a
budget refills at PARAM_VALUES_PER_S on a UDP or TCP link, and on a serial link at what half its bytes carry
(a PARAM_VALUE frame is PARAM_VALUE_BYTES long, 10 bits a byte on the wire), and holds at most 0.1 s of it.
"""

from __future__ import annotations

PARAM_VALUES_PER_S = 1000
"""How fast a parameter list goes out on a UDP or TCP link; a serial link gets half its bytes at most."""
PARAM_VALUE_BYTES = 37
BURST_S = 0.1
"""The budget holds at most this long's worth of messages."""


def param_rate(kind: str, baud: int) -> float:
    """PARAM_VALUE messages per second on a link of ``kind`` (an endpoint's kind: "serial", "udp"...)."""
    if kind != "serial":
        return PARAM_VALUES_PER_S
    return max(1.0, baud / 10 / 2 / PARAM_VALUE_BYTES)


class ParamPacer:
    """``pacer.allow(now_us, sending)``: how many PARAM_VALUE messages may go out now."""

    def __init__(self, rate_per_s: float, now_us: int) -> None:
        self.rate = rate_per_s
        self.budget = 0.0
        self._last_us = now_us

    def allow(self, now_us: int, sending: bool) -> int:
        """Refill for the time since the last call and take the whole messages the budget holds; while nothing is
        being sent the budget stays at one message, so that a list starts at once."""
        elapsed = (now_us - self._last_us) * 1e-6
        self._last_us = now_us
        if not sending:
            self.budget = 1.0
            return 0
        self.budget = min(self.budget + elapsed * self.rate, self.rate * BURST_S)
        count = int(self.budget)
        self.budget -= count
        return count
