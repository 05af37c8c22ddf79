"""InProcessAttitudeFlight: the lockstep chain in one process flies like the multi-process stack.

The first test flies a 10° roll step from hover. The second replays the seed-1 ``stack fly
attitude_step`` flight into it: the same profile parameters and seed, and at each step the attitude
setpoint and arming state the multi-process attitude controller and allocator could see (what was
published before that step), and compares the two ground truths up to the scenario's last tick.
They are close but not identical (see the test).
"""

from __future__ import annotations

import bisect
import math
import tomllib
from collections.abc import Callable

import pytest

from stack.mathlib import quaternion as quat
from stack.scenario.metrics import step_response
from stack.sim.inprocess import InProcessAttitudeFlight, StepRecord
from tests.flight.flights import Flight
from tests.support.harness import REPO

Fly = Callable[..., Flight]
STEP_DEG = 10.0


def profile_params() -> dict[str, object]:
    return tomllib.loads((REPO / "launch" / "sitl_quad.toml").read_text())["params"]


def finite(record: StepRecord) -> bool:
    t = record.truth
    values = (*t.position, *t.velocity, *t.q, *t.angular_velocity, *record.estimate, *record.rate_setpoint)
    return all(math.isfinite(v) for v in values)


def test_flies_a_roll_step_from_hover() -> None:
    flight = InProcessAttitudeFlight("sih_quad", profile_params(), seed=1)
    model = flight.sim.model
    flight.sim.reset_pose((0.0, 0.0, -5.0), motor_states=(model.hover_command,) * model.rotor_count)
    flight.armed = True
    flight.thrust = model.hover_thrust_fraction
    records = [flight.step() for _ in range(250)]  # 1 s of hover
    t_step = records[-1].time_us * 1e-6
    flight.q_sp = quat.from_euler(math.radians(STEP_DEG), 0.0, quat.yaw(records[-1].estimate))
    records += [flight.step() for _ in range(375)]  # 1.5 s holding the step
    assert all(finite(r) for r in records)
    times = [r.time_us * 1e-6 for r in records]
    roll = [math.degrees(quat.to_euler(r.truth.q)[0]) for r in records]
    start = roll[249]
    assert abs(start) < 1.0
    rise, overshoot = step_response(times, roll, t_step, start, start + STEP_DEG)
    assert 0.0 < rise < 0.15
    assert overshoot < 20.0
    assert roll[-1] == pytest.approx(STEP_DEG, abs=1.0)
    assert records[-1].truth.position[2] == pytest.approx(-5.0, abs=2.0)
    assert not records[-1].truth.on_ground


def replay(flight: Flight) -> tuple[list[StepRecord], dict[int, object]]:
    """Fly the recorded flight's setpoints and arming in one process; also return the recorded truth."""
    setpoints = [(m.pub_time_us, m.msg) for m in flight.messages("vehicle_attitude_setpoint")]
    armed = [(m.pub_time_us, m.msg.armed) for m in flight.messages("actuator_armed")]
    truth = {m.pub_time_us: m.msg for m in flight.messages("sim_groundtruth")}
    setpoint_times, armed_times = [t for t, _ in setpoints], [t for t, _ in armed]
    inproc = InProcessAttitudeFlight("sih_quad", profile_params(), seed=flight.report["seed"])
    step_us = inproc.sim.imu_period_us
    end = flight.scenario_end_us()
    records = []
    while inproc.sim.time_us + step_us <= end:
        t = inproc.sim.time_us + step_us
        # In lockstep a module acting at t sees what was published before t.
        i = bisect.bisect_left(setpoint_times, t)
        if i:
            sp = setpoints[i - 1][1]
            inproc.q_sp, inproc.thrust = sp.q_d, -sp.thrust_body[2]
        j = bisect.bisect_left(armed_times, t)
        inproc.armed = bool(j and armed[j - 1][1])
        records.append(inproc.step())
    return records, truth


@pytest.mark.flight
def test_matches_the_multiprocess_flight(fly: Fly) -> None:
    records, truth = replay(fly(1))
    assert len(records) > 2500
    assert all(finite(r) for r in records)
    attitude = [math.degrees(quat.angle_between(r.truth.q, truth[r.time_us].q)) for r in records]
    position = [math.dist(r.truth.position, truth[r.time_us].position) for r in records]
    # Not bit for bit: InProcessAttitudeFlight gives the estimator the magnetometer (and GPS) sample
    # of the same step, while in lockstep the estimator, triggered by the gyro, sees the simulator's
    # mag one step later (it is published after the gyro); and it leaves out the commander's land
    # detector and modes. With seed 1 the attitudes stay within about 1° and the positions within
    # a few tenths of a metre over the ~15 s flight.
    assert max(attitude) < 2.0, f"attitude differs by up to {max(attitude):.3f}°"
    assert max(position) < 1.0, f"position differs by up to {max(position):.3f} m"
