"""MAVLink time synchronisation (TIMESYNC): the peer's clock mapped onto ours, I/O-free.

After PX4's ``src/lib/timesync/Timesync.cpp``: each reply gives an offset sample ``(ts1 + now) / 2 - tc1`` (the
round trip assumed symmetric); samples whose round trip exceeds ``max_rtt_us`` are rejected; a double exponential
filter smooths the offset and tracks its drift (skew), its gains moving from 0.05 to 0.003 along a sigmoid over
the first 500 samples; a run of samples far from the estimate (a reboot or time jump of the peer) resets it.

Two departures from PX4: the skew is a rate (µs of offset per µs of local time) rather than a change per sample,
so irregular reply times do not bias it; and the estimate counts as ``synced`` after a few samples (PX4 waits for
all 500, 50 s at 10 Hz, before it maps any stamp), since the first sample is already within rtt/2 and the stack
must start flying before that. Outlier rejection starts there too.
"""

from __future__ import annotations

import math
from collections import deque

ALPHA_GAIN_INITIAL = 0.05
BETA_GAIN_INITIAL = 0.05
ALPHA_GAIN_FINAL = 0.003
BETA_GAIN_FINAL = 0.003
CONVERGENCE_WINDOW = 500
MAX_RTT_US = 10_000
MAX_DEVIATION_US = 100_000
MAX_CONSECUTIVE_HIGH_DEVIATION = 5
SYNCED_SAMPLES = 5
OUTSTANDING_REQUESTS = 32


class TimeSync:
    def __init__(self, *, max_rtt_us: int = MAX_RTT_US, max_deviation_us: int = MAX_DEVIATION_US) -> None:
        self.max_rtt_us = max_rtt_us
        self.max_deviation_us = max_deviation_us
        self.offset_us = 0.0  # local = remote + offset
        self.skew = 0.0  # d(offset)/d(local time)
        self.rtt_us = 0  # of the last reply, accepted or not
        self.samples = 0
        self.rejected_rtt = 0
        self.resets = 0
        self._high_deviation = 0
        self._sample_time_us = 0
        self._outstanding: deque[int] = deque(maxlen=OUTSTANDING_REQUESTS)

    @property
    def synced(self) -> bool:
        return self.samples >= SYNCED_SAMPLES

    def request(self, now_us: int) -> int:
        """The ts1 of a new request (tc1 = 0), in ns as MAVLink wants; its reply is recognised by it."""
        ts1_ns = now_us * 1000
        self._outstanding.append(ts1_ns)
        return ts1_ns

    def on_reply(self, tc1_ns: int, ts1_ns: int, now_us: int) -> None:
        """A reply: tc1 the peer's time when it answered, ts1 our request's. Replies to others are ignored."""
        if ts1_ns not in self._outstanding:
            return
        self._outstanding.remove(ts1_ns)
        sent_us = ts1_ns // 1000
        self.rtt_us = now_us - sent_us
        if self.rtt_us > self.max_rtt_us:
            self.rejected_rtt += 1
            return
        offset = (sent_us + now_us) / 2 - tc1_ns / 1000
        if self.synced and abs(offset - self._predicted_offset(now_us)) > self.max_deviation_us:
            self._high_deviation += 1
            if self._high_deviation > MAX_CONSECUTIVE_HIGH_DEVIATION:
                self.reset()
                self.resets += 1
            return
        self._high_deviation = 0
        self._add_sample(offset, now_us)

    def to_local_us(self, remote_us: int) -> int:
        """A peer timestamp on our clock (meaningful once synced)."""
        local = remote_us + self.offset_us
        return round(local + self.skew * (local - self._sample_time_us))

    def reset(self) -> None:
        self.offset_us = 0.0
        self.skew = 0.0
        self.samples = 0
        self._high_deviation = 0

    def _predicted_offset(self, now_us: int) -> float:
        return self.offset_us + self.skew * (now_us - self._sample_time_us)

    def _add_sample(self, offset: float, now_us: int) -> None:
        if self.samples == 0:
            self.offset_us = offset
        else:
            alpha, beta = self._gains()
            dt = now_us - self._sample_time_us
            previous = self.offset_us
            self.offset_us = alpha * offset + (1 - alpha) * self._predicted_offset(now_us)
            if dt > 0:
                self.skew = beta * (self.offset_us - previous) / dt + (1 - beta) * self.skew
        self._sample_time_us = now_us
        self.samples += 1

    def _gains(self) -> tuple[float, float]:
        if self.samples >= CONVERGENCE_WINDOW:
            return ALPHA_GAIN_FINAL, BETA_GAIN_FINAL
        progress = self.samples / CONVERGENCE_WINDOW
        p = 1.0 - math.exp(0.5 * (1.0 - 1.0 / (1.0 - progress)))
        return p * ALPHA_GAIN_FINAL + (1 - p) * ALPHA_GAIN_INITIAL, p * BETA_GAIN_FINAL + (1 - p) * BETA_GAIN_INITIAL
