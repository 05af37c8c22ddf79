"""The attitude_estimator_q module on a bench: the accelerometer sample it pairs with each gyro sample, what it
publishes and stamps, the backlog rule and its 10 Hz summaries (PX4 src/modules/attitude_estimator_q and the
sensors module's vehicle_angular_velocity)."""

import pytest

from stack.estimator.attitude_module import AttitudeEstimatorModule
from stack.estimator.imu_summary import STATUS_INTERVAL_US
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorGyro, SensorMag
from tests.support.bench import ModuleBench

DT = 0.004
G = 9.80665


def gyro_step(bench: ModuleBench, x=0.0, accel=True) -> None:
    t = bench.now + round(DT * 1e6)
    if accel:
        bench.put(ORB_ID.sensor_accel, SensorAccel(timestamp_sample=t, z=-G))
    bench.run(SensorGyro(timestamp_sample=t, x=x), DT)


def aligned(**params) -> ModuleBench:
    bench = ModuleBench(AttitudeEstimatorModule, params)
    for _ in range(1000):
        if bench.module.estimator.initialised:
            return bench
        bench.put(ORB_ID.sensor_mag, SensorMag(x=0.2, z=0.4))
        gyro_step(bench)
    raise AssertionError("no alignment in 4 s of a still vehicle")


def test_reads_and_writes_the_topics_of_px4s_modules():
    bench = ModuleBench(AttitudeEstimatorModule)
    assert set(bench.inputs) == {
        (t.name, 0) for t in (ORB_ID.sensor_accel, ORB_ID.sensor_mag, ORB_ID.vehicle_local_position, ORB_ID.sensor_gps)
    }
    assert set(bench.outputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_angular_velocity, ORB_ID.vehicle_attitude, ORB_ID.vehicle_imu_status,
                  ORB_ID.estimator_status)
    }


def test_rates_from_the_first_sample_attitude_only_once_aligned_both_stamped_with_the_gyro_sample():
    bench = ModuleBench(AttitudeEstimatorModule)
    gyro_step(bench, accel=False)
    rates = bench.sent(ORB_ID.vehicle_angular_velocity)
    assert len(rates) == 1 and rates[0].timestamp_sample == bench.now
    assert bench.sent(ORB_ID.vehicle_attitude) == []  # no accelerometer yet: nothing to align on
    bench = aligned()
    gyro_step(bench)
    att = bench.sent(ORB_ID.vehicle_attitude)[-1]
    assert att.timestamp_sample == bench.sent(ORB_ID.vehicle_angular_velocity)[-1].timestamp_sample == bench.now
    assert att.q == bench.module.estimator.q


def test_behind_integrates_every_sample_but_publishes_none():
    bench = aligned()
    sent = len(bench.sent(ORB_ID.vehicle_angular_velocity)), len(bench.sent(ORB_ID.vehicle_attitude))
    bench.behind = True
    q = bench.module.estimator.q
    gyro_step(bench, x=1.0)
    assert bench.module.estimator.q != q
    assert (len(bench.sent(ORB_ID.vehicle_angular_velocity)), len(bench.sent(ORB_ID.vehicle_attitude))) == sent


def test_each_gyro_sample_meets_its_own_accelerometer_sample():
    bench = ModuleBench(AttitudeEstimatorModule)
    for t in (1000, 2000, 3000):
        bench.put(ORB_ID.sensor_accel, SensorAccel(timestamp_sample=t, z=-float(t)))
        bench.module._accels.extend(bench.module.take(ORB_ID.sensor_accel))
    assert bench.module._accel_at(2500).z == -2000.0
    assert bench.module._accel_at(3000).z == -3000.0
    assert bench.module._accel_at(9000).z == -3000.0  # the newest before it


def test_summaries_at_ten_hertz():
    bench = aligned()
    start = len(bench.sent(ORB_ID.estimator_status))
    steps = round(STATUS_INTERVAL_US / (DT * 1e6))
    for _ in range(3 * steps):
        gyro_step(bench)
    statuses = bench.sent(ORB_ID.estimator_status)[start:]
    assert len(statuses) == 3
    assert statuses[-1].attitude_valid and statuses[-1].q == bench.module.estimator.q
    assert len(bench.sent(ORB_ID.vehicle_imu_status)) == len(bench.sent(ORB_ID.estimator_status))


def test_a_gyro_cutoff_change_reaches_the_filter():
    bench = aligned(IMU_GYRO_CUTOFF=0.0)
    gyro_step(bench, x=1.0)
    assert bench.sent(ORB_ID.vehicle_angular_velocity)[-1].xyz[0] == pytest.approx(1.0, abs=0.01)  # unfiltered
    bench.set_param("IMU_GYRO_CUTOFF", 5.0)
    gyro_step(bench, x=0.0)
    assert bench.sent(ORB_ID.vehicle_angular_velocity)[-1].xyz[0] > 0.5  # the low-pass holds the step back
