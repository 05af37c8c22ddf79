"""The world clock of a swarm (stack.runtime.world_clock): a vehicle runs at most SLACK_US ahead of every other one,
and once it must wait, waits until each has finished the step before its own; a vehicle that left, or whose
coordinator is gone, is waited for no more."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

from stack.runtime.world_clock import LEFT, SLACK_US, World, WorldClock, create_world, leave_world

P = 4000
NAMES = ["v1", "v2"]


def waits(clock: WorldClock, t_us: int) -> threading.Thread:
    thread = threading.Thread(target=clock.wait, args=(t_us, P), daemon=True)
    thread.start()
    return thread


def test_a_vehicle_runs_at_most_the_slack_ahead_and_then_waits_for_the_others_to_catch_up(tmp_path):
    path = tmp_path / "world"
    create_world(path, 2)
    a, b = WorldClock(path, 0, NAMES), WorldClock(path, 1, NAMES)
    ahead = SLACK_US // P
    try:
        for k in range(1, ahead + 1):  # as far as the slack goes without v2
            a.wait(k * P, P)
            a.done(k * P)
        blocked = waits(a, (ahead + 1) * P)
        blocked.join(0.3)
        assert blocked.is_alive(), "v1 ran more than the slack ahead of v2"
        for k in range(1, ahead):
            b.wait(k * P, P)
            b.done(k * P)
        blocked.join(0.3)
        assert blocked.is_alive(), "v1 went on before v2 had caught up"
        b.wait(ahead * P, P)
        b.done(ahead * P)
        blocked.join(5.0)
        assert not blocked.is_alive()
    finally:
        a.close()
        b.close()


def test_a_vehicle_that_left_or_whose_coordinator_is_gone_is_waited_for_no_more(tmp_path):
    path = tmp_path / "world"
    create_world(path, 2)
    a = WorldClock(path, 0, NAMES)
    try:
        blocked = waits(a, SLACK_US + 3 * P)
        blocked.join(0.2)
        assert blocked.is_alive()
        leave_world(path, 1)
        blocked.join(5.0)
        assert not blocked.is_alive()
    finally:
        a.close()
    create_world(path, 2)
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    world = World(path)
    world.set_pid(1, int(gone.stdout))
    world.close()
    a = WorldClock(path, 0, NAMES)
    try:
        start = time.monotonic()
        a.wait(SLACK_US + 3 * P, P)  # returns once it finds v2's pid gone
        assert time.monotonic() - start < 5.0
    finally:
        a.close()
    world = World(path)
    assert world.done_us(0) == world.done_us(1) == LEFT  # v1 left on close
    world.close()


VEHICLE = """
import sys
from pathlib import Path
from stack.runtime.world_clock import WorldClock
clock = WorldClock(Path(sys.argv[1]), 1, ["v1", "v2"])
for k in range(1, int(sys.argv[2]) + 1):
    clock.wait(k * 4000, 4000)
    clock.done(k * 4000)
clock.close()
"""


def test_two_processes_keep_within_the_slack_of_each_other(tmp_path):
    path = tmp_path / "world"
    create_world(path, 2)
    steps = 300
    other = subprocess.Popen([sys.executable, "-c", VEHICLE, str(path), str(steps)])
    clock = WorldClock(path, 0, NAMES)
    world = clock.world
    try:
        for k in range(1, steps + 1):
            clock.wait(k * P, P)
            other_done = world.done_us(1)
            assert other_done >= k * P - SLACK_US, (k, other_done, world.pid(1), world.seq(1), other.poll())
            # It cannot run more than the slack ahead of this one's last step (after its last step it leaves).
            assert other_done <= (k - 1) * P + SLACK_US + P or other_done == LEFT
            clock.done(k * P)
    finally:
        clock.close()
        assert other.wait(30) == 0
