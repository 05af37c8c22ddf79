"""Simulator physics throughput: physics steps per second in one process.

Run with ``python benchmarks/bench_sim_physics.py``. For each vehicle it prints the bare rigid-body
step rate (``MulticopterPhysics.step`` at 1 kHz) and the rate with sensors (``Simulator.advance``:
4 physics steps, wind, IMU every call, magnetometer, barometer and GPS at their rates), plus the
cost of ``Simulator.truth()``; for the planes (``--planes``), the real-time factor of their plants with sensors;
each figure is the best of ``--repeat`` runs. Reference points: RotorPy 3.0.0
(``Multirotor.step``, RK45 at 100 Hz, measured on the 2-core reference machine) ≈ 500 steps/s;
gym-pybullet-drones ≈ 4,000 (its README on the ``paper`` branch: 240 Hz physics at 15.5–16.8× real time);
a plain numpy RK4 quad (17 states, measured on the same machine) ≈ 7,700; target ≥ 50,000 with sensors.
"""

from __future__ import annotations

import argparse
import math
import time

from stack.airframe.model import FixedwingModel, load_vehicle
from stack.mathlib import quaternion as quat
from stack.sim.fixedwing_physics import level_trim
from stack.sim.physics import MulticopterPhysics
from stack.sim.simulator import Simulator
from stack.sim.wind import WindParams


def commands_for(model) -> tuple[float, ...]:
    """Slightly uneven hover commands, so the body rotates and every term of the model is exercised."""
    hover = model.hover_command
    return tuple(hover + 0.002 * (-1) ** i for i in range(model.rotor_count))


def bench_bare(name: str, steps: int) -> float:
    model = load_vehicle(name)
    commands = commands_for(model)
    physics = MulticopterPhysics(model)
    physics.reset(position=(0.0, 0.0, -100.0), motor_states=commands)
    step = physics.step
    wind = (1.0, 0.5, 0.0)
    start = time.perf_counter()
    for _ in range(steps):
        step(0.001, commands, wind)
    return steps / (time.perf_counter() - start)


def bench_with_sensors(name: str, steps: int) -> tuple[float, float]:
    sim = Simulator(name, seed=1, wind=WindParams(mean_ned=(1.0, 0.5, 0.0), gust_std_horizontal=0.5))
    commands = commands_for(sim.model)
    sim.reset_pose((0.0, 0.0, -100.0), motor_states=commands)
    advance = sim.advance
    substeps = sim.imu_period_us // 1000
    calls = steps // substeps
    start = time.perf_counter()
    for _ in range(calls):
        advance(commands)
    rate = calls * substeps / (time.perf_counter() - start)
    start = time.perf_counter()
    for _ in range(10_000):
        sim.truth()
    truth_us = (time.perf_counter() - start) / 10_000 * 1e6
    return rate, truth_us


def bench_plane(name: str, imu_periods: int) -> float:
    """Real-time factor of a fixed-wing plant's ``advance`` (sensors included) in trimmed flight at 15 m/s
    (SIH airplane at 500 Hz physics) or on the runway at idle (JSBSim, whose trim is its own)."""
    model = load_vehicle(name)
    if isinstance(model, FixedwingModel):
        sim = Simulator(model, seed=1, physics_rate_hz=500.0)
        trim = level_trim(model, 15.0, sim.home[2] + 100.0)
        speed = 15.0
        sim.reset_pose(
            (0.0, 0.0, -100.0), quat.from_euler(0.0, trim.pitch, 0.0),
            (speed * math.cos(trim.pitch), 0.0, -speed * math.sin(trim.pitch)), motor_states=(trim.throttle,),
        )
        commands: tuple[float, ...] = (trim.throttle, 0.0, trim.elevator, 0.0)
    else:
        from stack.sim.jsbsim_plant import JsbsimPlant

        sim = JsbsimPlant(model, seed=1, physics_rate_hz=500.0)
        commands = (0.0, 0.0, 0.0, 0.0)
    start = time.perf_counter()
    for _ in range(imu_periods):
        sim.advance(commands)
    return imu_periods * sim.imu_period_us * 1e-6 / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000, help="physics steps per measurement")
    parser.add_argument("--vehicles", nargs="+", default=["sih_quad", "firefly"])
    parser.add_argument("--planes", nargs="+", default=["sih_plane", "jsbsim_c172"])
    parser.add_argument("--repeat", type=int, default=3, help="report the best of this many measurements")
    args = parser.parse_args()
    print(f"{'vehicle':<12} {'bare steps/s':>14} {'µs/step':>8} {'with sensors':>14} {'µs/step':>8} {'truth() µs':>10}")
    for name in args.vehicles:
        bare = max(bench_bare(name, args.steps) for _ in range(args.repeat))
        runs = [bench_with_sensors(name, args.steps) for _ in range(args.repeat)]
        full = max(r[0] for r in runs)
        truth_us = min(r[1] for r in runs)
        print(f"{name:<12} {bare:>14,.0f} {1e6 / bare:>8.2f} {full:>14,.0f} {1e6 / full:>8.2f} {truth_us:>10.2f}")
    for name in args.planes:
        factor = max(bench_plane(name, args.steps // 20) for _ in range(args.repeat))
        print(f"{name:<12} plant with sensors at {factor:,.0f}× real time")


if __name__ == "__main__":
    main()
