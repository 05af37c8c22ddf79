"""The JSBSim plant (Cessna 172P): runway at rest, takeoff, control signs, sample schedule, determinism,
frame conversions, wind, resets, brakes and the vehicle file."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from stack.airframe.model import load_vehicle
from stack.mathlib import quaternion as quat
from stack.mathlib.atmosphere import AIR_DENSITY_SEA_LEVEL, isa_pressure_pa
from stack.sim.airspeed_sensor import AirspeedSample, air_density
from stack.sim.jsbsim_plant import FT, JsbsimPlant
from stack.sim.sensors import BaroSample, GpsSample, ImuParams, ImuSample, MagParams, MagSample
from stack.sim.simulator import SIH_HOME
from stack.sim.wind import WindParams

G = 9.80665
IDLE = (0.0, 0.0, 0.0, 0.0)
QUIET_IMU = ImuParams(gyro_noise_density=0.0, gyro_random_walk=0.0, accel_noise_density=0.0, accel_random_walk=0.0)


def plant(**kwargs) -> JsbsimPlant:
    kwargs.setdefault("physics_rate_hz", 250.0)
    return JsbsimPlant("jsbsim_c172", **kwargs)


def run(p: JsbsimPlant, commands: tuple[float, ...], advances: int) -> list:
    samples = []
    for _ in range(advances):
        samples.extend(p.advance(commands))
    return samples


def euler_deg(p: JsbsimPlant) -> tuple[float, float, float]:
    roll, pitch, yaw = quat.to_euler(p.truth().q)
    return math.degrees(roll), math.degrees(pitch), math.degrees(yaw)


def flying(p: JsbsimPlant, speed: float = 36.0, height: float = 300.0) -> None:
    """Level flight north at ``speed`` m/s at the trim pitch."""
    p.reset_pose((0.0, 0.0, -height), quat.from_euler(0.0, math.radians(4.0), 0.0), (speed, 0.0, 0.0))


def test_at_rest_it_stays_put_on_the_runway_and_the_sensors_read_gravity_and_home() -> None:
    p = plant(seed=3)
    start = p.truth()
    samples = run(p, IDLE, 2500)  # 10 s, disarmed: throttle 0, the brakes hold it against the idle thrust
    truth = p.truth()
    assert truth.on_ground
    assert math.dist(truth.position[:2], start.position[:2]) < 0.01
    assert math.hypot(*truth.velocity) < 1e-3
    # At rest the C172 sits on its gear with the centre of gravity 1.33 m above the runway, 2.4° nose up,
    # level to 0.1° (the pilot sits on the left), heading north.
    roll, pitch, yaw = euler_deg(p)
    assert abs(roll) < 0.2 and 1.5 < pitch < 3.5 and abs(yaw) < 0.01
    assert -truth.position[2] == pytest.approx(1.33, abs=0.05)
    assert truth.alt == pytest.approx(SIH_HOME[2] + 1.33, abs=0.05)
    assert p.fdm["propulsion/engine/engine-rpm"] > 500.0  # the engine idles
    imu = [s for s in samples if isinstance(s, ImuSample)]
    mean_accel = [sum(s.accel[i] for s in imu) / len(imu) for i in range(3)]
    expected = quat.rotate_inv(truth.q, (0.0, 0.0, -G))
    assert mean_accel == pytest.approx(expected, abs=0.02)
    assert math.hypot(*(sum(s.gyro[i] for s in imu) / len(imu) for i in range(3))) < 0.003
    baro = [s.pressure_pa for s in samples if isinstance(s, BaroSample)]
    assert sum(baro) / len(baro) == pytest.approx(isa_pressure_pa(truth.alt), abs=1.0)
    gps = [s for s in samples if isinstance(s, GpsSample)]
    assert sum(s.alt_msl for s in gps) / len(gps) == pytest.approx(truth.alt, abs=0.3)
    assert sum(s.lat for s in gps) / len(gps) == pytest.approx(SIH_HOME[0], abs=1e-5)


def test_full_throttle_runs_down_the_runway_and_lifts_off_with_up_elevator() -> None:
    """The ground roll with the heading held by the rudder (and nose wheel), wings held level, elevator
    neutral until 29 m/s indicated, then +0.3 (nose up): liftoff after ~240 m at ~30 m/s indicated
    (the C172P manual: rotate at 55 KIAS = 28 m/s, ground roll 890 ft = 270 m at its 2400 lb gross
    weight; this one weighs 1880 lb)."""
    p = plant(imu=QUIET_IMU)
    ias = 0.0
    liftoff = None
    accel_check: list[tuple[float, float, float]] = []
    for i in range(250 * 30):
        truth = p.truth()
        roll, _, yaw = quat.to_euler(truth.q)
        rudder = max(-1.0, min(1.0, -3.0 * yaw - truth.angular_velocity[2] - 0.05 * truth.position[1]))
        aileron = max(-1.0, min(1.0, -1.5 * roll - 0.3 * truth.angular_velocity[0]))
        elevator = 0.3 if ias >= 29.0 else 0.0
        for s in p.advance((1.0, aileron, elevator, rudder)):
            if isinstance(s, AirspeedSample):
                ias = s.indicated_airspeed
            elif isinstance(s, ImuSample) and 2000 <= i < 2250:  # 8–9 s: rolling straight at full power
                accel_check.append((s.accel[0], math.hypot(*truth.velocity[:2]), quat.to_euler(truth.q)[1]))
        truth = p.truth()
        if liftoff is None and not truth.on_ground:
            liftoff = (truth.position, ias)
        if -truth.position[2] > 15.0:
            break
    assert liftoff is not None, "never left the runway"
    (north, east, _), liftoff_ias = liftoff
    assert 200.0 < north < 300.0
    assert abs(east) < 2.0
    assert 28.0 < liftoff_ias < 32.0
    assert -p.truth().position[2] > 15.0  # and it climbs away
    # The accelerometer reads the acceleration along the runway plus gravity's share at the pitch attitude.
    forward, speed, pitch = zip(*accel_check, strict=True)
    acceleration = (speed[-1] - speed[0]) / ((len(speed) - 1) * 0.004)
    mean_pitch = sum(pitch) / len(pitch)
    assert sum(forward) / len(forward) == pytest.approx(acceleration + G * math.sin(mean_pitch), abs=0.05)


@pytest.mark.parametrize(("channel", "rate_axis"), [(1, 0), (2, 1), (3, 2)], ids=["aileron", "elevator", "rudder"])
def test_positive_surface_outputs_give_positive_body_rates(channel: int, rate_axis: int) -> None:
    for sign in (1.0, -1.0):
        p = plant(imu=QUIET_IMU)
        flying(p)
        commands = [0.6, 0.0, 0.0, 0.0]
        commands[channel] = 0.5 * sign
        run(p, tuple(commands), 50)  # 0.2 s
        rates = p.truth().angular_velocity
        assert rates[rate_axis] * sign > 0.02, rates


def test_rudder_steers_the_nose_wheel() -> None:
    p = plant()
    run(p, (0.5, 0.0, 0.0, 0.0), 1500)  # taxiing at a few m/s
    assert p.truth().on_ground and math.hypot(*p.truth().velocity[:2]) > 1.0
    run(p, (0.5, 0.0, 0.0, 1.0), 125)
    assert p.truth().on_ground
    assert p.truth().angular_velocity[2] > 0.1  # nose right


def test_clock_and_sample_rates() -> None:
    p = plant(seed=1)
    samples = run(p, IDLE, 250)
    assert p.time_us == 1_000_000 and p.imu_period_us == 4000
    kinds = (ImuSample, MagSample, BaroSample, GpsSample, AirspeedSample)
    times = {t: [s.time_us for s in samples if isinstance(s, t)] for t in kinds}
    assert times[ImuSample] == list(range(4000, 1_000_001, 4000))
    assert times[MagSample] == list(range(4000, 1_000_001, 20_000))
    assert times[GpsSample] == list(range(4000, 1_000_001, 100_000))
    ticks = [-(-t // 4000) * 4000 for t in range(4000, 1_000_001, 50_000)]  # 20 Hz on the 4 ms grid
    assert times[BaroSample] == ticks
    assert times[AirspeedSample] == ticks


def test_rates_must_fit_the_clock() -> None:
    with pytest.raises(ValueError, match="whole multiple"):
        JsbsimPlant(physics_rate_hz=400.0, imu_rate_hz=250.0)
    with pytest.raises(ValueError, match="must not exceed"):
        JsbsimPlant(gps_rate_hz=500.0)


def test_same_seed_same_samples_and_another_seed_other_noise() -> None:
    commands = (0.7, 0.1, -0.05, 0.02)
    a, b, c = plant(seed=7), plant(seed=7), plant(seed=8)
    samples_a, samples_b, samples_c = run(a, commands, 500), run(b, commands, 500), run(c, commands, 500)
    assert samples_a == samples_b
    assert a.truth() == b.truth()
    assert samples_a != samples_c
    assert a.truth().position == c.truth().position  # the noise differs, the flight does not


def test_known_attitude_gives_the_quaternion_the_field_and_gravity() -> None:
    p = plant(imu=QUIET_IMU, mag=MagParams(noise=(0.0, 0.0, 0.0)))
    attitude = quat.from_euler(math.radians(20.0), math.radians(10.0), math.radians(-60.0))
    p.reset_pose((50.0, -20.0, -400.0), attitude, (20.0, -34.64, 1.0))
    truth = p.truth()
    assert quat.angle_between(truth.q, attitude) < 1e-6
    assert truth.position == pytest.approx((50.0, -20.0, -400.0), abs=1e-3)
    assert truth.velocity == pytest.approx((20.0, -34.64, 1.0), abs=1e-6)
    # JSBSim's own body-axis velocity, rotated by our body → NED quaternion, is its NED velocity.
    body = (p.fdm["velocities/u-fps"] * FT, p.fdm["velocities/v-fps"] * FT, p.fdm["velocities/w-fps"] * FT)
    assert quat.rotate(truth.q, body) == pytest.approx(truth.velocity, abs=1e-6)
    samples = p.advance((0.6, 0.0, 0.0, 0.0))
    mag = next(s for s in samples if isinstance(s, MagSample))
    assert mag.field == pytest.approx(quat.rotate_inv(p.truth().q, p.magnetometer.earth_field_ned), abs=1e-9)
    # Free of the ground, the accelerometer reads the aerodynamic and propeller forces: mostly lift, along −z.
    imu = next(s for s in samples if isinstance(s, ImuSample))
    assert imu.accel[2] < -2.0 and abs(imu.accel[1]) < 2.0


def test_at_rest_the_accelerometer_is_gravity_in_the_body_frame() -> None:
    p = plant(imu=QUIET_IMU)
    run(p, IDLE, 25)
    imu = p.advance(IDLE)[0]
    expected = quat.rotate_inv(p.truth().q, (0.0, 0.0, -G))
    assert imu.accel == pytest.approx(expected, abs=0.01)  # JSBSim's effective gravity at 47° N is 9.806
    assert p.truth().specific_force == imu.accel


def test_the_wind_blows_through_jsbsim_and_the_airspeed_sensor() -> None:
    p = plant(wind=WindParams.from_speed_direction(8.0, 0.0))  # 8 m/s from the north: a headwind, parked
    assert p.wind == pytest.approx((-8.0, 0.0, 0.0))
    samples = run(p, IDLE, 250)
    truth = p.truth()
    assert truth.wind == pytest.approx((-8.0, 0.0, 0.0))
    assert p.fdm["velocities/u-aero-fps"] * FT == pytest.approx(8.0 * math.cos(math.radians(2.4)), abs=0.05)
    airspeed = [s for s in samples if isinstance(s, AirspeedSample)]
    expected_ias = 8.0 * math.cos(math.radians(2.4)) * math.sqrt(air_density(truth.alt) / AIR_DENSITY_SEA_LEVEL)
    assert sum(s.indicated_airspeed for s in airspeed) / len(airspeed) == pytest.approx(expected_ias, abs=0.3)
    assert math.hypot(*truth.position[:2]) < 0.01  # the brakes hold it in the wind
    p.set_wind_enabled(False)
    run(p, IDLE, 2)
    assert not p.wind_enabled and p.wind == (0.0, 0.0, 0.0)
    assert abs(p.fdm["velocities/u-aero-fps"]) < 0.01


def test_gps_switch() -> None:
    p = plant()
    p.set_gps_enabled(False)
    gps = [s for s in run(p, IDLE, 50) if isinstance(s, GpsSample)]
    assert not p.gps_enabled and gps and all(s.fix_type == 0 and math.isnan(s.lat) for s in gps)


def test_reset_pose_keeps_the_clock_and_puts_it_back_on_the_runway() -> None:
    p = plant()
    run(p, (0.8, 0.0, 0.0, 0.0), 500)
    t = p.time_us
    flying(p)
    assert p.time_us == t and not p.truth().on_ground
    run(p, (0.6, 0.0, 0.0, 0.0), 25)
    assert math.hypot(*p.truth().velocity) == pytest.approx(36.0, abs=0.5)
    p.reset_pose((100.0, 10.0, 0.0), quat.from_euler(0.0, 0.0, math.radians(90.0)))
    run(p, IDLE, 250)
    truth = p.truth()
    assert truth.on_ground and math.hypot(*truth.velocity) < 0.02  # the engine spooling down from 0.6
    assert truth.position == pytest.approx((100.0, 10.0, -1.33), abs=0.05)
    assert euler_deg(p)[2] == pytest.approx(90.0, abs=0.05)
    with pytest.raises(ValueError, match="finite"):
        p.reset_pose((math.nan, 0.0, -10.0))


def test_brakes_after_touchdown_and_never_in_the_air() -> None:
    p = plant()
    for _ in range(250 * 30):  # accelerate straight down the runway to 20 m/s, nose wheel down
        yaw = quat.to_euler(p.truth().q)[2]
        p.advance((1.0, 0.0, -0.1, max(-1.0, min(1.0, -3.0 * yaw - p.truth().angular_velocity[2]))))
        if p.truth().velocity[0] >= 20.0:
            break
    assert p.fdm["fcs/left-brake-cmd-norm"] == 0.0  # throttle up: released
    start = p.truth().position[0]
    for _ in range(250 * 30):  # throttle to idle: the brakes stop it
        yaw = quat.to_euler(p.truth().q)[2]
        p.advance((0.0, 0.0, 0.0, max(-1.0, min(1.0, -3.0 * yaw - p.truth().angular_velocity[2]))))
        if math.hypot(*p.truth().velocity[:2]) < 0.05:
            break
    assert p.fdm["fcs/left-brake-cmd-norm"] == p.fdm["fcs/right-brake-cmd-norm"] == 0.5
    assert 60.0 < p.truth().position[0] - start < 150.0  # ~2 m/s² of braking; unbraked it rolls on for km
    flying(p)
    p.advance(IDLE)
    assert p.fdm["fcs/left-brake-cmd-norm"] == 0.0


def test_outputs_are_sanitised() -> None:
    a, b = plant(), plant()
    run(a, (math.nan, math.inf, -math.nan, 7.0), 10)
    run(b, (0.0, 0.0, 0.0, 1.0), 10)
    assert a.truth() == b.truth()
    assert a.fdm["fcs/throttle-cmd-norm"] == 0.0 and a.fdm["fcs/rudder-cmd-norm"] == -1.0
    with pytest.raises(ValueError, match="4 actuator outputs"):
        a.advance((0.5,))


def test_vehicle_file() -> None:
    model = load_vehicle("jsbsim_c172")
    assert model.aircraft == "c172p" and model.input_count == 4 and model.rotor_count == 1
    assert model.airframe["CA_AIRFRAME"] == 1
    assert plant().mass == pytest.approx(852.75, abs=0.5)


def test_vehicle_file_errors_name_the_key(tmp_path: Path) -> None:
    source = Path(load_vehicle("jsbsim_c172").path).read_text()
    cases = [
        (source.replace('type = "jsbsim"', 'type = "quad"'), "type"),
        (source.replace("rudder = [", "yaw = ["), "controls.yaw"),
        (source.replace("CA_AIRFRAME = 1", "CA_AIRFRAME = 0"), "airframe.CA_AIRFRAME"),
        (source.replace("command = 0.5", "command = 2.0"), "brakes.command"),
    ]
    for i, (text, key) in enumerate(cases):
        path = tmp_path / f"bad{i}.toml"
        path.write_text(text)
        with pytest.raises(ValueError, match=f"bad{i}.toml: {key}"):
            load_vehicle(path)
    model = dataclasses.replace(load_vehicle("jsbsim_c172"), aircraft="no_such_plane")
    with pytest.raises(ValueError, match="no aircraft 'no_such_plane'"):
        JsbsimPlant(model)
    path = tmp_path / "badprop.toml"
    path.write_text(source.replace("fcs/steer-cmd-norm", "fcs/steering-wheel"))
    with pytest.raises(ValueError, match="no property 'fcs/steering-wheel'"):
        JsbsimPlant(path)
