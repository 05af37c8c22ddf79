"""AngularVelocityFilter: DC gain, attenuation, derivative, bias, sample-rate changes, bad input."""

from __future__ import annotations

import math
import random

import pytest

from stack.estimator.angular_velocity import AngularVelocityFilter, GyroFilterParams

RATE_HZ = 250.0
DT_US = 4000


def run_sine(filt: AngularVelocityFilter, freq_hz: float, seconds: float, dt_us: int = DT_US) -> float:
    """Feed a unit sine on x and return the peak output amplitude over the last half."""
    n = int(seconds * 1e6 / dt_us)
    peak = 0.0
    for i in range(n):
        t_us = 1_000_000 + i * dt_us
        xyz, _ = filt.update(t_us, (math.sin(2.0 * math.pi * freq_hz * t_us * 1e-6), 0.0, 0.0))
        if i > n // 2:
            peak = max(peak, abs(xyz[0]))
    return peak


def test_first_sample_passes_through_with_zero_derivative() -> None:
    filt = AngularVelocityFilter()
    xyz, dxyz = filt.update(1_000_000, (0.3, -0.2, 0.1))
    assert xyz == pytest.approx((0.3, -0.2, 0.1), abs=1e-12)
    assert dxyz == (0.0, 0.0, 0.0)


def test_unity_dc_gain() -> None:
    filt = AngularVelocityFilter()
    filt.update(1_000_000, (0.0, 0.0, 0.0))
    for i in range(1, 500):
        xyz, dxyz = filt.update(1_000_000 + i * DT_US, (0.5, -1.0, 2.0))
    assert xyz == pytest.approx((0.5, -1.0, 2.0), abs=1e-9)
    assert dxyz == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)


def test_passes_low_and_attenuates_high_frequencies() -> None:
    assert run_sine(AngularVelocityFilter(), 5.0, 4.0) == pytest.approx(1.0, abs=0.03)
    # A 40 Hz Butterworth is -3 dB at 40 Hz and about -17 dB at 100 Hz (bilinear, 250 Hz).
    assert run_sine(AngularVelocityFilter(), 40.0, 2.0) == pytest.approx(math.sqrt(0.5), abs=0.05)
    assert run_sine(AngularVelocityFilter(), 100.0, 2.0) < 0.15


def test_reduces_white_noise() -> None:
    rng = random.Random(0)
    filt = AngularVelocityFilter(GyroFilterParams(imu_gyro_cutoff=20.0))
    out = []
    for i in range(5000):
        xyz, _ = filt.update(1_000_000 + i * DT_US, (rng.gauss(0.0, 1.0), 0.0, 0.0))
        out.append(xyz[0])
    std = math.sqrt(sum(v * v for v in out[100:]) / len(out[100:]))
    # Noise power scales with the bandwidth: about sqrt(20/125) of the input.
    assert std < 0.5


def test_derivative_of_a_ramp_is_its_slope() -> None:
    filt = AngularVelocityFilter()
    slope = (2.0, -0.5, 10.0)  # rad/s²
    for i in range(500):
        t = i * DT_US * 1e-6
        _, dxyz = filt.update(1_000_000 + i * DT_US, (slope[0] * t, slope[1] * t, slope[2] * t))
    assert dxyz == pytest.approx(slope, rel=1e-6)


def test_bias_is_subtracted_without_disturbing_the_derivative() -> None:
    filt = AngularVelocityFilter()
    for i in range(300):
        filt.update(1_000_000 + i * DT_US, (0.1, 0.2, 0.3))
    xyz, dxyz = filt.update(1_000_000 + 300 * DT_US, (0.1, 0.2, 0.3), bias=(0.01, -0.02, 0.03))
    assert xyz == pytest.approx((0.09, 0.22, 0.27), abs=1e-9)
    assert dxyz == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_derivative_uses_the_measured_interval() -> None:
    filt = AngularVelocityFilter(GyroFilterParams(imu_gyro_cutoff=0.0, imu_dgyro_cutoff=0.0))
    filt.update(1_000_000, (0.0, 0.0, 0.0))
    _, dxyz = filt.update(1_010_000, (0.1, 0.0, 0.0))  # one late sample: 10 ms
    assert dxyz[0] == pytest.approx(10.0)


def test_zero_cutoffs_disable_the_filters() -> None:
    filt = AngularVelocityFilter(GyroFilterParams(imu_gyro_cutoff=0.0, imu_dgyro_cutoff=0.0))
    rng = random.Random(1)
    prev = 0.0
    filt.update(1_000_000, (prev, 0.0, 0.0))
    for i in range(1, 50):
        x = rng.uniform(-1.0, 1.0)
        xyz, dxyz = filt.update(1_000_000 + i * DT_US, (x, 0.0, 0.0))
        assert xyz[0] == x
        assert dxyz[0] == pytest.approx((x - prev) * RATE_HZ)
        prev = x


def test_sample_rate_change_redesigns_the_filters() -> None:
    filt = AngularVelocityFilter(sample_rate_hz=RATE_HZ)
    t_us = 1_000_000
    for _ in range(200):
        t_us += DT_US
        filt.update(t_us, (0.4, 0.0, 0.0))
    assert filt.sample_rate_hz == RATE_HZ
    outputs = []
    for _ in range(200):
        t_us += 1000  # the gyro now runs at 1 kHz
        xyz, _ = filt.update(t_us, (0.4, 0.0, 0.0))
        outputs.append(xyz[0])
    assert filt.sample_rate_hz == pytest.approx(1000.0)
    assert outputs == pytest.approx([0.4] * len(outputs), abs=1e-9)  # no transient at the re-design
    # At 1 kHz a 100 Hz tone is well inside the new Nyquist band and only mildly attenuated by 40 Hz.
    tone = run_sine(filt, 100.0, 1.0, dt_us=1000)
    assert 0.1 < tone < 0.25


def test_non_finite_samples_are_ignored() -> None:
    filt = AngularVelocityFilter()
    for i in range(100):
        good = filt.update(1_000_000 + i * DT_US, (0.2, 0.0, 0.0))
    assert filt.update(1_400_000, (math.nan, 0.0, 0.0)) == good
    assert filt.update(1_404_000, (0.2, math.inf, 0.0)) == good
    assert filt.update(1_408_000, (0.2, 0.0, 0.0), bias=(math.nan, 0.0, 0.0)) == good
    xyz, dxyz = filt.update(1_412_000, (0.2, 0.0, 0.0))
    assert xyz == pytest.approx((0.2, 0.0, 0.0), abs=1e-9)
    assert dxyz == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)


def test_repeated_timestamp_assumes_one_nominal_interval() -> None:
    filt = AngularVelocityFilter(GyroFilterParams(imu_gyro_cutoff=0.0, imu_dgyro_cutoff=0.0))
    filt.update(1_000_000, (0.0, 0.0, 0.0))
    _, dxyz = filt.update(1_000_000, (0.04, 0.0, 0.0))
    assert dxyz[0] == pytest.approx(0.04 * RATE_HZ)


def test_set_params_changes_the_cutoff() -> None:
    filt = AngularVelocityFilter()
    filt.set_params(GyroFilterParams(imu_gyro_cutoff=10.0))
    assert run_sine(filt, 40.0, 2.0) < 0.1


def test_derivative_is_taken_from_the_filtered_rate() -> None:
    filt = AngularVelocityFilter()
    freq = 100.0
    peak = 0.0
    for i in range(500):
        t_us = 1_000_000 + i * DT_US
        _, dxyz = filt.update(t_us, (math.sin(2.0 * math.pi * freq * t_us * 1e-6), 0.0, 0.0))
        if i > 250:
            peak = max(peak, abs(dxyz[0]))
    # Rate low-pass (~0.14) times D-term low-pass (~0.2) at 100 Hz; the D-term filter alone
    # would leave about 0.16 of the raw derivative amplitude 2π·f.
    assert peak < 0.05 * 2.0 * math.pi * freq
