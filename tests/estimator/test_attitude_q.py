"""AttitudeEstimatorQ: initialisation, convergence, gyro bias, gating and robustness (synthetic IMU)."""

from __future__ import annotations

import math
import random

import pytest

from stack.estimator import attitude_q
from stack.estimator.attitude_q import AttitudeEstimatorParams, AttitudeEstimatorQ
from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3

DT = 0.004  # 250 Hz IMU
INCLINATION = math.radians(63.0)  # Zürich
MAG_NORTH: Vec3 = (0.21 * math.cos(INCLINATION), 0.0, 0.21 * math.sin(INCLINATION))  # Gauss, NED


def earth_field(declination_deg: float = 0.0) -> Vec3:
    d = math.radians(declination_deg)
    return (MAG_NORTH[0] * math.cos(d), MAG_NORTH[0] * math.sin(d), MAG_NORTH[2])


def measure(
    q: Quat,
    rng: random.Random,
    omega: Vec3 = (0.0, 0.0, 0.0),
    bias: Vec3 = (0.0, 0.0, 0.0),
    accel_ned: Vec3 = (0.0, 0.0, 0.0),
    gyro_sigma: float = 0.01,
    accel_sigma: float = 0.1,
    mag_sigma: float = 0.005,
    field: Vec3 = MAG_NORTH,
) -> tuple[Vec3, Vec3, Vec3]:
    """Gyro, accelerometer and magnetometer readings of a vehicle at attitude q."""
    specific_force = quat.rotate_inv(q, (accel_ned[0], accel_ned[1], accel_ned[2] - CONSTANTS_ONE_G))
    field_body = quat.rotate_inv(q, field)

    def noisy(v: Vec3, sigma: float) -> Vec3:
        return (v[0] + rng.gauss(0.0, sigma), v[1] + rng.gauss(0.0, sigma), v[2] + rng.gauss(0.0, sigma))

    gyro = noisy((omega[0] + bias[0], omega[1] + bias[1], omega[2] + bias[2]), gyro_sigma)
    return gyro, noisy(specific_force, accel_sigma), noisy(field_body, mag_sigma)


def error_deg(a: Quat, b: Quat) -> float:
    return math.degrees(quat.angle_between(a, b))


def align(est: AttitudeEstimatorQ, q_true: Quat, rng: random.Random, mag_every: int = 5, **noise: float) -> int:
    """Feed a still vehicle's samples until the estimator has aligned; return how many it took."""
    for i in range(int(10.0 * attitude_q.ALIGN_TIME_S / DT)):
        gyro, accel, mag = measure(q_true, rng, **noise)
        if est.update(DT, gyro, accel, mag if i % mag_every == 0 else None):
            return i + 1
    raise AssertionError("never aligned")


def test_initialises_from_accel_and_mag_after_the_alignment_time() -> None:
    q_true = quat.from_euler(math.radians(10.0), math.radians(-20.0), math.radians(135.0))
    est = AttitudeEstimatorQ()
    steps = align(est, q_true, random.Random(0), gyro_sigma=0.0, accel_sigma=0.0, mag_sigma=0.0)
    assert steps * DT == pytest.approx(attitude_q.ALIGN_TIME_S, abs=DT)
    assert est.initialised
    assert error_deg(est.q, q_true) < 1e-4


def test_waits_for_the_magnetometer_before_initialising() -> None:
    est = AttitudeEstimatorQ()
    for _ in range(int(2.0 * attitude_q.ALIGN_TIME_S / DT)):
        assert not est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -CONSTANTS_ONE_G))
    assert not est.initialised


def test_averaging_removes_most_of_the_magnetometer_noise_from_the_initial_heading() -> None:
    # 0.02 G per axis in a 0.095 G horizontal field: one sample is ~12° of heading noise (RMS).
    errors = []
    for seed in range(20):
        est = AttitudeEstimatorQ()
        q_true = quat.from_euler(0.0, 0.0, math.radians(18.0 * seed))
        align(est, q_true, random.Random(seed), mag_sigma=0.02)
        errors.append(math.degrees(abs(quat.yaw(quat.mul(quat.conj(q_true), est.q)))))
    assert max(errors) < 6.0
    assert math.sqrt(sum(e * e for e in errors) / len(errors)) < 2.5


def test_motion_restarts_the_alignment() -> None:
    est = AttitudeEstimatorQ()
    rng = random.Random(4)
    for _ in range(int(0.9 * attitude_q.ALIGN_TIME_S / DT)):
        assert not est.update(DT, *measure(quat.IDENTITY, rng, gyro_sigma=0.0)[0:2])
    gyro, accel, mag = measure(quat.IDENTITY, rng, omega=(0.0, 0.0, 1.0))
    assert not est.update(DT, gyro, accel, mag)
    steps = align(est, quat.IDENTITY, rng, gyro_sigma=0.0)
    assert steps * DT == pytest.approx(attitude_q.ALIGN_TIME_S, abs=DT)


def test_without_magnetometer_starts_at_yaw_zero() -> None:
    q_true = quat.from_euler(math.radians(15.0), 0.0, 0.0)
    est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_w_mag=0.0))
    align(est, q_true, random.Random(0), accel_sigma=0.0)
    assert error_deg(est.q, q_true) < 1e-4


def test_declination_is_applied_at_initialisation() -> None:
    q_true = quat.from_euler(math.radians(20.0), math.radians(-10.0), math.radians(30.0))
    est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_mag_decl=12.0))
    align(est, q_true, random.Random(0), gyro_sigma=0.0, accel_sigma=0.0, mag_sigma=0.0, field=earth_field(12.0))
    assert error_deg(est.q, q_true) < 1e-4


def test_declination_change_rotates_the_estimate() -> None:
    est = AttitudeEstimatorQ()
    est.reset(quat.from_euler(0.0, 0.0, math.radians(40.0)))
    est.set_params(AttitudeEstimatorParams(att_mag_decl=5.0))
    assert math.degrees(quat.yaw(est.q)) == pytest.approx(45.0, abs=1e-9)


@pytest.mark.parametrize("noise", [False, True])
def test_converges_from_wrong_attitude_while_static(noise: bool) -> None:
    rng = random.Random(1)
    q_true = quat.from_euler(math.radians(5.0), math.radians(-3.0), math.radians(60.0))
    est = AttitudeEstimatorQ()
    est.reset(quat.mul(q_true, quat.from_euler(math.radians(30.0), 0.0, math.radians(90.0))))
    sigma = 1.0 if noise else 0.0
    errors = []
    for i in range(int(120.0 / DT)):
        gyro, accel, mag = measure(
            q_true, rng, gyro_sigma=0.01 * sigma, accel_sigma=0.3 * sigma, mag_sigma=0.01 * sigma
        )
        assert est.update(DT, gyro, accel, mag if i % 5 == 0 else None)
        errors.append(error_deg(est.q, q_true))
    assert errors[0] > 90.0
    assert max(errors[int(100.0 / DT) :]) < 1.5
    roll, pitch, _ = quat.to_euler(quat.mul(quat.conj(q_true), est.q))
    # Tilt converges much faster than heading (ATT_W_ACC is twice ATT_W_MAG and needs no bias).
    assert math.degrees(math.hypot(roll, pitch)) < 2.0


def test_converges_while_rotating() -> None:
    rng = random.Random(2)
    est = AttitudeEstimatorQ()
    q_true = quat.from_euler(0.0, 0.0, 0.0)
    est.reset(quat.mul(q_true, quat.from_euler(math.radians(30.0), math.radians(-10.0), math.radians(90.0))))
    errors = []
    for i in range(int(90.0 / DT)):
        t = i * DT
        # Yawing at 0.6 rad/s while rocking in roll and pitch.
        omega = (0.4 * math.cos(1.3 * t), 0.3 * math.sin(0.9 * t), 0.6)
        q_true = quat.integrate(q_true, omega, DT)
        gyro, accel, mag = measure(q_true, rng, omega=omega)
        assert est.update(DT, gyro, accel, mag)
        errors.append(error_deg(est.q, q_true))
    assert errors[0] > 90.0
    assert max(errors[int(60.0 / DT) :]) < 3.0


def test_fast_spin_boosts_the_heading_correction() -> None:
    def heading_error_after(spin_rate: float) -> float:
        est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_w_acc=0.0))
        q_true = quat.IDENTITY
        est.reset(quat.from_euler(0.0, 0.0, math.radians(20.0)))
        rng = random.Random(3)
        for _ in range(int(1.0 / DT)):
            q_true = quat.integrate(q_true, (0.0, 0.0, spin_rate), DT)
            gyro, accel, mag = measure(q_true, rng, omega=(0.0, 0.0, spin_rate), gyro_sigma=0.0, mag_sigma=0.0)
            est.update(DT, gyro, accel, mag)
        return math.degrees(abs(quat.yaw(quat.mul(quat.conj(q_true), est.q))))

    slow = heading_error_after(0.5)
    fast = heading_error_after(3.0)
    # Below 50 deg/s the error decays by exp(-0.1 t); at 3 rad/s the gain is 3/0.873 times higher.
    assert slow == pytest.approx(20.0 * math.exp(-0.1), rel=0.05)
    assert fast == pytest.approx(20.0 * math.exp(-0.1 * 3.0 / 0.873), rel=0.05)


def test_gyro_bias_converges_to_injected_bias() -> None:
    rng = random.Random(4)
    bias = (0.02, -0.015, 0.01)
    q_true = quat.from_euler(math.radians(-4.0), math.radians(6.0), math.radians(-100.0))
    est = AttitudeEstimatorQ()
    for _ in range(int(150.0 / DT)):
        gyro, accel, mag = measure(q_true, rng, bias=bias)
        est.update(DT, gyro, accel, mag)
    for i in range(3):
        assert est.gyro_bias[i] == pytest.approx(bias[i], abs=2e-3)
    assert error_deg(est.q, q_true) < 1.0
    for i in range(3):
        assert est.rates[i] == pytest.approx(0.0, abs=0.05)


def test_bias_is_not_learned_while_rotating_fast() -> None:
    rng = random.Random(5)
    est = AttitudeEstimatorQ()
    q_true = quat.IDENTITY
    omega = (0.0, 0.0, 0.3)  # above the 0.175 rad/s learning limit
    est.reset(quat.from_euler(0.2, 0.0, 0.0))
    for _ in range(int(20.0 / DT)):
        q_true = quat.integrate(q_true, omega, DT)
        gyro, accel, mag = measure(q_true, rng, omega=omega, bias=(0.02, 0.0, 0.0))
        est.update(DT, gyro, accel, mag)
    assert est.gyro_bias == (0.0, 0.0, 0.0)


def test_bias_is_clamped_to_att_bias_max() -> None:
    rng = random.Random(6)
    est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_bias_max=0.03))
    for _ in range(int(60.0 / DT)):
        gyro, accel, mag = measure(quat.IDENTITY, rng, bias=(0.1, 0.0, 0.0), gyro_sigma=0.0)
        est.update(DT, gyro, accel, mag)
    assert est.gyro_bias[0] == pytest.approx(0.03, abs=1e-12)
    est.set_params(AttitudeEstimatorParams(att_bias_max=0.01))
    assert est.gyro_bias[0] == pytest.approx(0.01, abs=1e-12)


def test_accel_outside_gate_is_ignored() -> None:
    est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_w_mag=0.0, att_w_gyro_bias=0.0))
    q0 = quat.from_euler(math.radians(20.0), 0.0, 0.0)
    est.reset(q0)
    # 1.5 g straight down in body: outside the 0.9–1.1 g gate, so no tilt correction at all.
    for _ in range(500):
        assert est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -1.5 * CONSTANTS_ONE_G))
    assert error_deg(est.q, q0) < 1e-4
    # Inside the gate the same reading levels the estimate: 20° · exp(−ATT_W_ACC · 30 s) ≈ 0.05°.
    for _ in range(int(30.0 / DT)):
        est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -CONSTANTS_ONE_G))
    assert error_deg(est.q, quat.IDENTITY) < 0.1


def test_acceleration_compensation_removes_the_manoeuvre_tilt() -> None:
    accel_ned = (3.0, 0.0, 0.0)  # level, accelerating north: inside the gate (1.05 g)

    def final_error(compensate: bool) -> float:
        rng = random.Random(7)
        est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_acc_comp=int(compensate)))
        est.reset(quat.IDENTITY)
        for _ in range(int(30.0 / DT)):
            gyro, accel, mag = measure(quat.IDENTITY, rng, accel_ned=accel_ned)
            est.update(DT, gyro, accel, mag, accel_compensation=accel_ned)
        return error_deg(est.q, quat.IDENTITY)

    assert final_error(compensate=False) > 10.0  # it levels against the tilted specific force
    assert final_error(compensate=True) < 1.0


def test_rejects_non_finite_and_overflowing_inputs() -> None:
    est = AttitudeEstimatorQ()
    rng = random.Random(8)
    align(est, quat.IDENTITY, rng)
    q, bias = est.q, est.gyro_bias
    nan = math.nan
    assert not est.update(DT, (nan, 0.0, 0.0), (0.0, 0.0, -9.8))
    assert not est.update(DT, (0.0, 0.0, 0.0), (0.0, math.inf, -9.8))
    assert not est.update(DT, (1e300, 0.0, 0.0), (0.0, 0.0, -9.8))
    assert not est.update(nan, (0.0, 0.0, 0.0), (0.0, 0.0, -9.8))
    assert not est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert (est.q, est.gyro_bias) == (q, bias)
    # A non-finite or overflowing magnetometer sample is not kept.
    assert est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -9.8), (nan, 0.0, 0.0))
    assert est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -9.8), (1e300, 1e300, 0.0))
    assert quat.is_finite(est.q)
    assert error_deg(est.q, q) < 0.1


def test_non_finite_result_reverts_and_resets_bias(monkeypatch: pytest.MonkeyPatch) -> None:
    est = AttitudeEstimatorQ()
    est.reset(quat.IDENTITY)
    est.gyro_bias = (0.01, 0.01, 0.01)
    monkeypatch.setattr(attitude_q.quat, "integrate", lambda q, w, dt: (math.nan,) * 4)
    assert not est.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, -CONSTANTS_ONE_G))
    assert est.q == quat.IDENTITY
    assert est.gyro_bias == (0.0, 0.0, 0.0)


def test_dt_is_clamped_to_20_ms() -> None:
    est = AttitudeEstimatorQ(AttitudeEstimatorParams(att_w_acc=0.0, att_w_mag=0.0))
    est.reset(quat.IDENTITY)
    assert est.update(1.0, (0.0, 0.0, 1.0), (0.0, 0.0, -CONSTANTS_ONE_G))
    assert quat.yaw(est.q) == pytest.approx(0.02, abs=1e-12)
