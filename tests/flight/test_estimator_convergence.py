"""attitude_estimator_q converges from a wrong initial attitude on the simulator's own sensors.

tests/estimator/test_attitude_q.py checks convergence on synthetic Gaussian readings; here the
readings come from the simulator's sensor models as a flight sees them (IMU white noise and
Gauss–Markov bias, magnetometer noise and declination, mag at 50 Hz), in one process. The filter
starts 30° off in roll and 90° off in yaw (about 94° in all).
"""

from __future__ import annotations

import math

import pytest

from stack.estimator.attitude_q import AttitudeEstimatorParams, AttitudeEstimatorQ
from stack.mathlib import quaternion as quat
from stack.sim.sensors import ImuSample, MagSample
from stack.sim.simulator import Simulator

DURATION_S = 120.0
OFFSET = quat.from_euler(math.radians(30.0), 0.0, math.radians(90.0))


@pytest.mark.parametrize(
    ("airborne", "yaw_deg", "seed"),
    [(False, 60.0, 1), (True, -120.0, 2)],
    ids=["on-the-ground", "hovering"],
)
def test_converges_from_30_deg_roll_and_90_deg_yaw_off(airborne: bool, yaw_deg: float, seed: int) -> None:
    sim = Simulator("sih_quad", seed=seed)
    model = sim.model
    attitude = quat.from_euler(0.0, 0.0, math.radians(yaw_deg))
    # Hovering: motors at the hover command, the vehicle held in the air by its own thrust.
    commands = (model.hover_command if airborne else 0.0,) * model.rotor_count
    sim.reset_pose((0.0, 0.0, -20.0 if airborne else 0.0), attitude, motor_states=commands)
    declination = sim.magnetometer.params.declination_deg
    estimator = AttitudeEstimatorQ(AttitudeEstimatorParams(att_mag_decl=declination))
    estimator.reset(quat.mul(attitude, OFFSET))
    dt = sim.imu_period_us * 1e-6
    errors, tilt_errors = [], []
    for _ in range(round(DURATION_S / dt)):
        samples = sim.advance(commands)
        imu = next(s for s in samples if isinstance(s, ImuSample))
        mag = next((s.field for s in samples if isinstance(s, MagSample)), None)
        assert estimator.update(dt, imu.gyro, imu.accel, mag)
        truth = sim.truth()
        errors.append(math.degrees(quat.angle_between(estimator.q, truth.q)))
        roll, pitch, _ = quat.to_euler(quat.mul(quat.conj(truth.q), estimator.q))
        tilt_errors.append(math.degrees(math.hypot(roll, pitch)))
    per_s = round(1.0 / dt)
    assert errors[0] > 90.0
    assert sim.truth().position[2] == pytest.approx(-20.0 if airborne else 0.0, abs=0.5)  # it stayed put
    # The heading (ATT_W_MAG 0.1/s) takes about a minute from 90° off; the tilt settles first.
    assert max(errors[60 * per_s :]) < 4.0
    assert max(errors[100 * per_s :]) < 1.5
    assert max(tilt_errors[60 * per_s :]) < 0.5
    # The learned gyro bias is the simulated one.
    for learned, true in zip(estimator.gyro_bias, sim.imu.gyro_bias, strict=True):
        assert learned == pytest.approx(true, abs=0.002)
