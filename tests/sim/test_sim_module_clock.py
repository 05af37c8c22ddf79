"""The simulator module keeps simulated time on the wall clock in real time: a late run catches up on the steps it
missed, up to MAX_CATCH_UP_STEPS; beyond that the missed time is skipped and counted. In lockstep each run is one
step."""

from __future__ import annotations

import itertools

from stack.msg.registry import ORB_ID
from stack.sim.module import SimulatorModule
from stack.sim.simulator import MAX_CATCH_UP_STEPS
from tests.support.bench import ModuleBench

PERIOD_S = 0.004


def imu_times(bench: ModuleBench) -> list[int]:
    return [m.timestamp_sample for m in bench.sent(ORB_ID.sensor_gyro)]


def test_one_step_per_run_when_on_time():
    bench = ModuleBench(SimulatorModule)
    for _ in range(10):
        bench.run(None, PERIOD_S)
    times = imu_times(bench)
    assert len(times) == 10 and all(b - a == 4000 for a, b in itertools.pairwise(times))
    assert times[-1] == bench.now
    assert bench.module.status() == {
        "catch_up_steps": 0, "skipped_steps": 0, "motor_control": "stack", "plant_mode": ""
    }


def test_a_late_run_catches_up_then_keeps_to_the_clock():
    bench = ModuleBench(SimulatorModule)
    bench.run(None, PERIOD_S)
    bench.run(None, 10 * PERIOD_S)  # ten periods late: the nine missed steps run now, back to back
    times = imu_times(bench)
    assert len(times) == 11 and times[-1] == bench.now
    assert all(b - a == 4000 for a, b in itertools.pairwise(times))
    assert bench.module.status()["catch_up_steps"] == 9
    bench.run(None, PERIOD_S)
    assert imu_times(bench)[-1] == bench.now


def test_beyond_the_catch_up_limit_the_missed_time_is_skipped():
    bench = ModuleBench(SimulatorModule)
    bench.run(None, PERIOD_S)
    late = MAX_CATCH_UP_STEPS + 50
    bench.run(None, late * PERIOD_S)
    times = imu_times(bench)
    assert len(times) == 2 and times[-1] == bench.now  # one step, stamped now: the stack's clock again
    assert bench.module.status() == {
        "catch_up_steps": 0, "skipped_steps": late - 1, "motor_control": "stack", "plant_mode": ""
    }
    assert bench.module.sim.time_us == 2 * 4000  # the physics did not see the skipped time
    truth = bench.sent(ORB_ID.sim_groundtruth)
    assert truth[-1].timestamp_sample == bench.now


def test_an_early_run_steps_nothing():
    bench = ModuleBench(SimulatorModule)
    bench.run(None, PERIOD_S)
    bench.run(None, 0.001)
    assert len(imu_times(bench)) == 1
