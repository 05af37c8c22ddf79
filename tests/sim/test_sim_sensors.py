"""Sensor models: noise statistics against the configured figures, ISA barometer, magnetic field, GPS."""

from __future__ import annotations

import itertools
import math
import random
import statistics

import pytest

from stack.mathlib.atmosphere import isa_altitude_m, isa_pressure_pa, isa_temperature_k
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import IDENTITY, from_euler
from stack.sim.sensors import (
    BarometerModel,
    BaroParams,
    GpsModel,
    GpsParams,
    ImuModel,
    ImuParams,
    MagnetometerModel,
    MagParams,
)

G = 9.80665
RATE = 250.0


def axis_stats(vectors: list[tuple[float, float, float]], axis: int) -> tuple[float, float]:
    x = [v[axis] for v in vectors]
    return statistics.fmean(x), statistics.pstdev(x)


def test_imu_white_noise_matches_noise_density() -> None:
    params = ImuParams(gyro_random_walk=0.0, accel_random_walk=0.0)
    imu = ImuModel(params, RATE, random.Random(1))
    samples = [imu.sample(i, (0.1, -0.2, 0.3), (0.0, 0.0, -G)) for i in range(20000)]
    gyro_sigma = params.gyro_noise_density * math.sqrt(RATE)  # 5.37e-3 rad/s
    accel_sigma = params.accel_noise_density * math.sqrt(RATE)  # 0.063 m/s²
    for axis, truth in enumerate((0.1, -0.2, 0.3)):
        mean, std = axis_stats([s.gyro for s in samples], axis)
        assert mean == pytest.approx(truth, abs=4 * gyro_sigma / math.sqrt(20000))
        assert std == pytest.approx(gyro_sigma, rel=0.03)
    for axis, truth in enumerate((0.0, 0.0, -G)):
        mean, std = axis_stats([s.accel for s in samples], axis)
        assert mean == pytest.approx(truth, abs=4 * accel_sigma / math.sqrt(20000))
        assert std == pytest.approx(accel_sigma, rel=0.03)
    assert samples[0].temperature == 15.0


def test_imu_bias_follows_the_random_walk() -> None:
    params = ImuParams(gyro_noise_density=0.0, accel_noise_density=0.0)
    imu = ImuModel(params, RATE, random.Random(2))
    samples = [imu.sample(i, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)) for i in range(20000)]
    dt = 1.0 / RATE
    for vectors, walk in (([s.gyro for s in samples], params.gyro_random_walk),
                          ([s.accel for s in samples], params.accel_random_walk)):
        steps = [b[0] - a[0] for a, b in itertools.pairwise(vectors)]
        assert statistics.pstdev(steps) == pytest.approx(walk * math.sqrt(dt), rel=0.03)
    assert samples[-1].accel == pytest.approx(imu.accel_bias, abs=1e-12)
    assert samples[-1].gyro == pytest.approx(imu.gyro_bias, abs=1e-12)


def test_imu_turn_on_bias_spread() -> None:
    params = ImuParams(gyro_noise_density=0.0, gyro_random_walk=0.0, gyro_turn_on_bias_sigma=8.7e-3,
                       accel_noise_density=0.0, accel_random_walk=0.0, accel_turn_on_bias_sigma=0.196)
    biases = [ImuModel(params, RATE, random.Random(seed)).sample(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
              for seed in range(600)]
    assert statistics.pstdev([b.gyro[1] for b in biases]) == pytest.approx(8.7e-3, rel=0.12)
    assert statistics.pstdev([b.accel[2] for b in biases]) == pytest.approx(0.196, rel=0.12)


def test_magnetometer_field_and_noise() -> None:
    params = MagParams()
    mag = MagnetometerModel(params, random.Random(3))
    fn, fe, fd = mag.earth_field_ned
    assert math.degrees(math.atan2(fe, fn)) == pytest.approx(params.declination_deg)
    assert math.degrees(math.atan2(fd, math.hypot(fn, fe))) == pytest.approx(params.inclination_deg)
    assert math.sqrt(fn * fn + fe * fe + fd * fd) == pytest.approx(params.strength_gauss)
    samples = [mag.sample(i, IDENTITY).field for i in range(10000)]
    for axis in range(3):
        mean, std = axis_stats(samples, axis)
        assert mean == pytest.approx(mag.earth_field_ned[axis], abs=0.002)
        assert std == pytest.approx(params.noise[axis], rel=0.04)


def test_magnetometer_rotates_into_body() -> None:
    mag = MagnetometerModel(MagParams(noise=(0.0, 0.0, 0.0), offset=(0.01, 0.0, -0.02)), random.Random(4))
    fn, fe, fd = mag.earth_field_ned
    # Heading east: body x points east, body y points south.
    field = mag.sample(0, from_euler(0.0, 0.0, math.pi / 2.0)).field
    assert field == pytest.approx((fe + 0.01, -fn, fd - 0.02), abs=1e-12)


def test_isa_hand_worked_values() -> None:
    assert isa_pressure_pa(0.0) == pytest.approx(101325.0)
    assert isa_pressure_pa(1000.0) == pytest.approx(89874.6, abs=1.0)  # standard atmosphere table
    assert isa_temperature_k(1000.0) == pytest.approx(281.65)
    assert isa_altitude_m(isa_pressure_pa(489.4)) == pytest.approx(489.4, abs=1e-9)


def test_barometer_noise_offsets_and_temperature() -> None:
    baro = BarometerModel(BaroParams(noise_pa=2.0, offset_pa=30.0, offset_temperature=1.5), random.Random(5))
    samples = [baro.sample(i, 500.0) for i in range(10000)]
    pressures = [s.pressure_pa for s in samples]
    assert statistics.fmean(pressures) == pytest.approx(isa_pressure_pa(500.0) + 30.0, abs=0.1)
    assert statistics.pstdev(pressures) == pytest.approx(2.0, rel=0.04)
    assert samples[0].temperature == pytest.approx(288.15 - 0.0065 * 500.0 - 273.15 + 1.5)


HOME = (47.397742, 8.545594, 489.4)


def gps_model(params: GpsParams, seed: int = 6) -> GpsModel:
    return GpsModel(params, 10.0, MapProjection(HOME[0], HOME[1]), HOME[2], random.Random(seed))


def test_gps_noise_statistics() -> None:
    params = GpsParams()
    gps = gps_model(params)
    projection = MapProjection(HOME[0], HOME[1])
    north, east, down, vel = [], [], [], []
    for i in range(10000):
        gps.measure(i, (10.0, -5.0, -20.0), (1.0, 2.0, -0.5))
        s = gps.pop_due(i)
        n, e = projection.project(s.lat, s.lon)
        north.append(n)
        east.append(e)
        down.append(HOME[2] - s.alt_msl)
        vel.append(s.vel_ned)
        assert (s.fix_type, s.satellites, s.eph, s.epv) == (3, 10, 0.9, 1.78)
    for values, truth, sigma in ((north, 10.0, 0.2), (east, -5.0, 0.2), (down, -20.0, 0.5)):
        assert statistics.fmean(values) == pytest.approx(truth, abs=0.02)
        assert statistics.pstdev(values) == pytest.approx(sigma, rel=0.04)
    for axis, (truth, sigma) in enumerate(zip((1.0, 2.0, -0.5), params.velocity_noise, strict=True)):
        mean, std = axis_stats(vel, axis)
        assert mean == pytest.approx(truth, abs=0.01)
        assert std == pytest.approx(sigma, rel=0.04)


def test_gps_drift_is_slow_and_has_the_configured_spread() -> None:
    params = GpsParams(noise_horizontal=0.0, noise_vertical=0.0, drift_horizontal=1.5, drift_vertical=3.0,
                       drift_time_constant=20.0)
    projection = MapProjection(HOME[0], HOME[1])
    spreads_n, spreads_d, jumps = [], [], []
    for seed in range(200):
        gps = gps_model(params, seed)
        gps.measure(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        a = gps.pop_due(0)
        gps.measure(1, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        b = gps.pop_due(1)
        spreads_n.append(projection.project(a.lat, a.lon)[0])
        spreads_d.append(HOME[2] - a.alt_msl)
        jumps.append(projection.project(b.lat, b.lon)[0] - spreads_n[-1])
    assert statistics.pstdev(spreads_n) == pytest.approx(1.5, rel=0.15)
    assert statistics.pstdev(spreads_d) == pytest.approx(3.0, rel=0.15)
    # One 0.1 s step of a 20 s process moves the error by σ·√(1 − e^(−0.01)) ≈ 0.1·σ.
    assert statistics.pstdev(jumps) == pytest.approx(1.5 * math.sqrt(1.0 - math.exp(-0.01)), rel=0.15)


def test_gps_delay_and_no_fix_when_off() -> None:
    gps = gps_model(GpsParams(delay=0.25))
    assert gps.delay_us == 250_000
    gps.measure(100_000, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert gps.pop_due(349_999) is None
    sample = gps.pop_due(350_000)
    assert sample is not None and sample.time_us == 100_000
    gps.set_enabled(False)
    gps.measure(200_000, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    off = gps.pop_due(450_000)
    assert off.fix_type == 0 and off.satellites == 0
    assert math.isnan(off.lat) and math.isnan(off.vel_ned[0])
    assert off.eph == 100.0
