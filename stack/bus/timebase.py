"""One time base for a vehicle spread over several hosts, in real time.

Every timestamp of the stack is a host's CLOCK_MONOTONIC (PX4's ``hrt_absolute_time``), and timestamps cross hosts:
the commander judges estimates stamped on the simulator's host, an estimator fuses samples stamped on another.
Two machines' monotonic clocks count from their own boots, so the vehicle keeps one time base, the leading host's
(the host of the lockstep coordinator, which also leads the run: :mod:`stack.supervisor.supervisor`), and every
other host runs its modules on its own clock plus an offset to it, as PX4's MAVLink ``TIMESYNC`` puts a companion
computer on the autopilot's clock (``src/modules/mavlink/mavlink_timesync.cpp``):

* the supervisor of a host measures the offset before it starts its modules: SYNC_SAMPLES round trips to the
  leader's clock, keeping the one with the shortest round trip (the offset's error is at most half of it);
* it measures again every RESYNC_PERIOD_S and slews towards the new figure by at most MAX_SLEW_PPM of the time
  passed, so that no module's clock ever steps (or runs backwards); an error above SKEW_WARN_US is reported;
* its modules read the offset from a file of eight bytes it shares with them (:class:`SharedOffset`, named by
  the environment variable OFFSET_FILE_ENV); a process without one runs on its own clock (one host).
"""

from __future__ import annotations

import mmap
import os
import struct
from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple

OFFSET_FILE_ENV = "STACK_CLOCK_OFFSET_FILE"
SYNC_SAMPLES = 16
RESYNC_PERIOD_S = 5.0
MAX_SLEW_PPM = 1000
"""A millisecond per second at most: faster than any two crystals drift apart (tens of ppm), slow enough that a
module's time steps stay within a tenth of a percent of its period."""
SKEW_WARN_US = 20_000
_FORMAT = struct.Struct("<q")


class ClockSample(NamedTuple):
    sent_us: int
    """The local clock when the request went out."""
    remote_us: int
    """The leader's clock in its answer."""
    received_us: int
    """The local clock when the answer arrived."""


class OffsetEstimate(NamedTuple):
    offset_us: int
    """The leader's clock minus the local clock."""
    round_trip_us: int


def estimate_offset(samples: Iterable[ClockSample]) -> OffsetEstimate | None:
    """The offset from the sample of the shortest round trip (NTP's clock filter), or None without samples."""
    best: OffsetEstimate | None = None
    for s in samples:
        round_trip = s.received_us - s.sent_us
        if round_trip < 0:
            continue
        estimate = OffsetEstimate(s.remote_us - (s.sent_us + s.received_us) // 2, round_trip)
        if best is None or estimate.round_trip_us < best.round_trip_us:
            best = estimate
    return best


def slew(current_us: int, measured_us: int, elapsed_us: int) -> int:
    """The offset to use now: towards ``measured_us`` by at most MAX_SLEW_PPM of ``elapsed_us``."""
    limit = elapsed_us * MAX_SLEW_PPM // 1_000_000
    return current_us + max(-limit, min(limit, measured_us - current_us))


class SharedOffset:
    """The offset, in µs, in a file of eight bytes mapped into memory: the supervisor writes, its modules read."""

    def __init__(self, path: Path, writable: bool = False) -> None:
        self.path = path
        if writable:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
            os.ftruncate(fd, _FORMAT.size)
        else:
            fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
        try:
            access = mmap.ACCESS_WRITE if writable else mmap.ACCESS_READ
            self._map = mmap.mmap(fd, _FORMAT.size, access=access)
        finally:
            os.close(fd)

    def read(self) -> int:
        return _FORMAT.unpack_from(self._map)[0]

    def write(self, offset_us: int) -> None:
        # One aligned eight-byte store: a reader sees the old value or the new one.
        _FORMAT.pack_into(self._map, 0, offset_us)

    def close(self) -> None:
        self._map.close()


def shared_offset_from_environment() -> SharedOffset | None:
    """The offset this process's supervisor shares with it, if it gives one (OFFSET_FILE_ENV)."""
    path = os.environ.get(OFFSET_FILE_ENV)
    return SharedOffset(Path(path)) if path else None
