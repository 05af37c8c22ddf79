"""The vehicle's time base across hosts (stack.bus.timebase): the offset from the shortest round trip, a slew that
never steps, and the offset a supervisor shares with its modules' clocks."""

from __future__ import annotations

import os
import subprocess
import sys

from stack.bus.timebase import (
    MAX_SLEW_PPM,
    OFFSET_FILE_ENV,
    ClockSample,
    OffsetEstimate,
    SharedOffset,
    estimate_offset,
    slew,
)


def test_the_offset_is_the_one_of_the_shortest_round_trip():
    samples = [
        ClockSample(1_000, 101_000 + 900, 1_600),  # 600 µs round trip, answered late
        ClockSample(2_000, 102_150, 2_300),  # 300 µs: the best
        ClockSample(3_000, 103_000, 2_900),  # a clock that ran backwards: ignored
    ]
    assert estimate_offset(samples) == OffsetEstimate(100_000, 300)
    assert estimate_offset([]) is None


def test_the_offset_slews_by_at_most_its_rate_and_settles_on_the_measure():
    one_second = 1_000_000
    step = one_second * MAX_SLEW_PPM // 1_000_000
    assert slew(0, 50_000, one_second) == step
    assert slew(0, -50_000, one_second) == -step
    assert slew(0, 300, one_second) == 300


def test_a_module_reads_its_clock_on_the_vehicles_time_base(tmp_path):
    shared = SharedOffset(tmp_path / "clock_offset", writable=True)
    shared.write(100_000_000)
    assert (os.stat(tmp_path / "clock_offset").st_mode & 0o777) == 0o600
    code = "from stack.bus.node import wall_clock_us; import time; print(wall_clock_us() - time.monotonic_ns() // 1000)"
    env = {**os.environ, OFFSET_FILE_ENV: str(shared.path)}
    ahead = int(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True).stdout)
    assert 99_900_000 < ahead <= 100_000_000
    shared.write(-5)
    env.pop(OFFSET_FILE_ENV)
    same = int(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True).stdout)
    assert -100_000 < same <= 0  # no offset file: the host's own clock
    shared.close()
