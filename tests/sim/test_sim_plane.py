"""The SIH airplane in the simulator: airspeed at 20 Hz, ground truth, and the simulator module's glue."""

from __future__ import annotations

import math
from typing import Any

import pytest

from stack.mathlib.atmosphere import AIR_DENSITY_SEA_LEVEL
from stack.mathlib.quaternion import from_euler, rotate_inv
from stack.msg.actuators import ActuatorOutputs
from stack.msg.system import ActuatorArmed
from stack.params.store import ParamStore
from stack.runtime.spec import ModuleSpec, resolve_args
from stack.sim.airspeed_sensor import AirspeedParams, AirspeedSample, air_density
from stack.sim.fixedwing_physics import FixedwingPhysics, level_trim
from stack.sim.module import AIRSPEED_DEVICE_ID, SimulatorModule
from stack.sim.simulator import SIH_HOME, Simulator
from stack.sim.wind import WindParams

HOME_ALT = SIH_HOME[2]


def trimmed(sim: Simulator, airspeed: float, wind_north: float = 0.0, altitude: float = 100.0) -> tuple[float, ...]:
    """Put the plane in level flight north at ``airspeed`` through the air; return the trim commands."""
    trim = level_trim(sim.model, airspeed, HOME_ALT + altitude)
    sim.reset_pose((0.0, 0.0, -altitude), from_euler(0.0, trim.pitch, 0.0), (airspeed + wind_north, 0.0, 0.0),
                   motor_states=[trim.throttle])
    return (trim.throttle, 0.0, trim.elevator, 0.0)


def airspeed_samples(sim: Simulator, commands: tuple[float, ...], seconds: float) -> list[AirspeedSample]:
    samples = []
    for _ in range(round(seconds * 250)):
        samples.extend(s for s in sim.advance(commands) if isinstance(s, AirspeedSample))
    return samples


def test_the_plane_runs_on_fixedwing_physics_and_starts_at_rest_on_its_gear() -> None:
    sim = Simulator("sih_plane", physics_rate_hz=500)
    assert isinstance(sim.physics, FixedwingPhysics)
    truth = sim.truth()
    assert truth.on_ground and truth.position == (0.0, 0.0, 0.0) and truth.motors == (0.0,)
    assert truth.alt == pytest.approx(HOME_ALT)
    samples = []
    for _ in range(250):
        samples.extend(sim.advance((0.0, 0.0, 0.0, 0.0)))
    imu = [s for s in samples if not isinstance(s, AirspeedSample) and hasattr(s, "accel")]
    assert imu[-1].accel == pytest.approx((0.0, 0.0, -9.80665), abs=0.2)  # resting: the accelerometer reads −g
    assert sim.physics.position == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_airspeed_is_sampled_at_20_hz_on_the_imu_clock() -> None:
    sim = Simulator("sih_plane", seed=4, physics_rate_hz=500)
    commands = trimmed(sim, 15.0)
    samples = airspeed_samples(sim, commands, 1.0)
    assert [s.time_us for s in samples] == [-(-t // 4000) * 4000 for t in range(4000, 1_000_001, 50_000)]


def test_airspeed_in_still_air_is_the_forward_air_speed() -> None:
    sim = Simulator("sih_plane", seed=4, physics_rate_hz=500, airspeed=AirspeedParams(noise_pa=0.0))
    commands = trimmed(sim, 15.0)
    s = airspeed_samples(sim, commands, 0.05)[0]
    p = sim.physics
    forward = rotate_inv(p.attitude, p.velocity)[0]
    assert forward == pytest.approx(15.0 * math.cos(math.radians(2.31)), abs=0.005)  # the pitot sees V·cos α
    rho = air_density(HOME_ALT - p.position[2])
    assert s.true_airspeed == pytest.approx(forward, rel=1e-9)
    assert s.indicated_airspeed == pytest.approx(forward * math.sqrt(rho / AIR_DENSITY_SEA_LEVEL), rel=1e-9)
    assert s.differential_pressure == pytest.approx(0.5 * rho * forward**2, rel=1e-9)


@pytest.mark.parametrize("wind_north", [-8.0, 5.0])
def test_airspeed_in_wind_is_relative_to_the_air_not_the_ground(wind_north: float) -> None:
    wind = WindParams.from_speed_direction(abs(wind_north), 0.0 if wind_north < 0 else 180.0, enabled=True)
    sim = Simulator("sih_plane", seed=4, physics_rate_hz=500, wind=wind)
    commands = trimmed(sim, 15.0, wind_north=wind_north)
    samples = airspeed_samples(sim, commands, 2.0)
    assert sim.wind[0] == pytest.approx(wind_north)
    assert sim.physics.velocity[0] == pytest.approx(15.0 + wind_north, abs=0.05)  # ground speed
    mean = sum(s.true_airspeed for s in samples) / len(samples)
    assert mean == pytest.approx(15.0, abs=0.05)  # 1 Pa of noise: ±0.06 m/s per sample


def test_multicopters_have_no_airspeed_sensor() -> None:
    sim = Simulator("sih_quad")
    samples = []
    for _ in range(50):
        samples.extend(sim.advance((0.0,) * 4))
    assert not any(isinstance(s, AirspeedSample) for s in samples)


# ---------------------------------------------------------------------------------------------- the module


class _Input:
    def __init__(self) -> None:
        self.latest: Any = None
        self.queue: list[Any] = []

    def take(self) -> list[Any]:
        messages, self.queue = self.queue, []
        return messages

    def update(self) -> Any:
        return None  # the tests set ``latest``: no new message counts as arrived


class _Output:
    def __init__(self) -> None:
        self.messages: list[Any] = []

    def publish(self, msg: Any, now_us: int) -> None:
        self.messages.append(msg)


class StandInRuntime:
    """What the simulator module reads from its runtime, in memory."""

    def __init__(self, vehicle: str) -> None:
        self.name = SimulatorModule.NAME
        self.spec = ModuleSpec(name=self.name, module="stack.sim.module:SimulatorModule", seed=3)
        self.params = ParamStore(SimulatorModule.PARAMS, {})
        self.args = resolve_args(SimulatorModule.ARGS, {"vehicle": vehicle, "physics_rate_hz": 500.0})
        self.inputs: dict[tuple[str, int], _Input] = {}
        self.outputs: dict[tuple[str, int], _Output] = {}
        self.now = 0

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        self.inputs[(topic, instance)] = _Input()

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        self.outputs[(topic, instance)] = _Output()

    def now_us(self) -> int:
        return self.now

    def published(self, topic: str) -> list[Any]:
        return self.outputs[(topic, 0)].messages


def run(module: SimulatorModule, rt: StandInRuntime, seconds: float) -> None:
    for _ in range(round(seconds * 1e6 / module.step_period_us())):
        rt.now += module.step_period_us()
        module.run(None, module.step_period_us() * 1e-6)


def outputs(*values: float) -> ActuatorOutputs:
    return ActuatorOutputs(noutputs=len(values), output=(*values, *(0.0,) * (16 - len(values))))


def test_the_module_publishes_airspeed_at_20_hz_for_the_plane() -> None:
    rt = StandInRuntime("sih_plane")
    module = SimulatorModule(rt)
    assert module.input_count == 4
    run(module, rt, 1.0)
    airspeed = rt.published("airspeed")
    assert len(airspeed) == 20
    first = airspeed[0]
    assert first.device_id == AIRSPEED_DEVICE_ID and first.confidence == 1.0
    assert [m.timestamp_sample for m in airspeed[:2]] == [4000, 56000]  # 4 ms ticks at or after 0, 50 ms
    assert all(abs(m.differential_pressure_pa) < 5.0 for m in airspeed)  # at rest: only the 1 Pa of noise
    assert math.isfinite(first.air_temperature_celsius) and math.isfinite(first.differential_pressure_pa)


def test_the_module_takes_the_plane_inputs_from_actuator_outputs_sim_while_armed() -> None:
    rt = StandInRuntime("sih_plane")
    module = SimulatorModule(rt)
    rt.inputs[("actuator_outputs_sim", 0)].latest = outputs(0.5, 0.0, math.nan, 0.0, 0.9)
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=False)  # the stack, disarmed first
    assert module.motor_commands() == (0.0, 0.0, 0.0, 0.0)
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=True)
    assert module.motor_commands() == (0.5, 0.0, 0.0, 0.0)  # four inputs, NaN → 0, the fifth output ignored
    run(module, rt, 0.5)
    truth = rt.published("sim_groundtruth")[-1]
    assert truth.motors == (pytest.approx(0.5, abs=1e-3),)  # the throttle state after ten time constants
    assert truth.velocity[0] > 1.0  # it rolls
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=False)
    assert module.motor_commands() == (0.0, 0.0, 0.0, 0.0)


def test_the_multicopter_module_still_has_no_airspeed_topic() -> None:
    rt = StandInRuntime("sih_quad")
    module = SimulatorModule(rt)
    assert module.input_count == 4
    assert ("airspeed", 0) not in rt.outputs
    run(module, rt, 0.1)
    assert len(rt.published("sensor_gyro")) == 25
