"""The world clock of a swarm (stack.runtime.world_clock): a vehicle begins a step only once every other one has
finished the step before it; a vehicle that left, or whose coordinator is gone, is waited for no more."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

from stack.runtime.world_clock import LEFT, World, WorldClock, create_world, leave_world

P = 4000
NAMES = ["v1", "v2"]


def waits(clock: WorldClock, t_us: int) -> threading.Thread:
    thread = threading.Thread(target=clock.wait, args=(t_us, P), daemon=True)
    thread.start()
    return thread


def test_a_step_waits_for_every_other_vehicle_to_finish_the_step_before(tmp_path):
    path = tmp_path / "world"
    create_world(path, 2)
    a, b = WorldClock(path, 0, NAMES), WorldClock(path, 1, NAMES)
    try:
        a.wait(P, P)  # the first step waits for nobody
        a.done(P)
        blocked = waits(a, 2 * P)
        blocked.join(0.3)
        assert blocked.is_alive(), "v1 began its second step before v2 finished its first"
        b.wait(P, P)
        b.done(P)
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
        blocked = waits(a, 3 * P)
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
        a.wait(3 * P, P)  # returns once it finds v2's pid gone
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


def test_two_processes_keep_within_one_step_of_each_other(tmp_path):
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
            assert other_done >= (k - 1) * P
            # It cannot begin step k + 1 before this one finished step k (after its last step it leaves).
            assert other_done <= k * P or (other_done == LEFT and k == steps)
            clock.done(k * P)
    finally:
        clock.close()
        assert other.wait(30) == 0
