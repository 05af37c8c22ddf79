"""The local_position_estimator module on a bench: what it needs before it runs, what it fuses, what it publishes
and stamps, and the samples it refuses (PX4 src/modules/local_position_estimator/BlockLocalPositionEstimator.cpp)."""

import math

import pytest

from stack.estimator.position_kf import LocalPositionKF
from stack.estimator.position_module import ATTITUDE_TIMEOUT_US, LocalPositionEstimatorModule
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorBaro
from stack.msg.system import VehicleLandDetected
from tests.support.bench import ModuleBench

DT = 0.02
G = 9.80665


def step(bench: ModuleBench, az=-G, pressure=101325.0) -> None:
    t = bench.now + round(DT * 1e6)
    bench.put(ORB_ID.sensor_accel, SensorAccel(timestamp_sample=t - 500, z=az))
    if pressure is not None:
        bench.put(ORB_ID.sensor_baro, SensorBaro(timestamp_sample=t - 500, pressure=pressure))
    bench.run(None, DT)


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(LocalPositionEstimatorModule)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.sensor_accel, ORB_ID.sensor_baro, ORB_ID.sensor_gps, ORB_ID.vehicle_attitude,
                  ORB_ID.vehicle_land_detected, ORB_ID.airspeed_validated, ORB_ID.wind)
    }
    assert set(bench.outputs) == {(ORB_ID.vehicle_local_position.name, 0), (ORB_ID.vehicle_global_position.name, 0)}


def test_silent_without_an_attitude_and_the_measurements_of_then_are_dropped():
    bench = ModuleBench(LocalPositionEstimatorModule)
    step(bench)
    assert bench.sent(ORB_ID.vehicle_local_position) == []
    assert bench.module.update(ORB_ID.sensor_baro) is None  # taken, not kept for later


def test_publishes_both_positions_stamped_with_the_accelerometer_sample_and_heading_from_the_attitude():
    bench = ModuleBench(LocalPositionEstimatorModule)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude(q=quat.from_euler(0.0, 0.0, 0.7)))
    step(bench)
    step(bench)
    local = bench.sent(ORB_ID.vehicle_local_position)[-1]
    glob = bench.sent(ORB_ID.vehicle_global_position)[-1]
    assert local.timestamp_sample == glob.timestamp_sample == bench.now - 500
    assert local.timestamp == glob.timestamp == bench.now
    assert local.heading == pytest.approx(0.7) and local.heading_good_for_control


def test_silent_once_the_attitude_is_older_than_its_timeout_and_again_publishing_when_it_is_back():
    """The attitude estimator gone (dead, or its host lost) while the sensors go on: no estimate, valid or not."""
    bench = ModuleBench(LocalPositionEstimatorModule)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude(timestamp_sample=0))
    while bench.now + round(DT * 1e6) - 500 <= ATTITUDE_TIMEOUT_US:
        step(bench)
    published = len(bench.sent(ORB_ID.vehicle_local_position))
    assert published == ATTITUDE_TIMEOUT_US // round(DT * 1e6)
    for _ in range(50):
        step(bench)
    assert len(bench.sent(ORB_ID.vehicle_local_position)) == published
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude(timestamp_sample=bench.now))
    step(bench)
    assert len(bench.sent(ORB_ID.vehicle_local_position)) == published + 1


def test_a_non_finite_accelerometer_sample_is_refused_and_counted():
    bench = ModuleBench(LocalPositionEstimatorModule)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude())
    step(bench)
    step(bench, az=math.nan)
    assert bench.rejected == 1


def test_the_barometer_is_fused_as_an_isa_altitude_and_a_zero_pressure_skipped(monkeypatch):
    fused = []
    monkeypatch.setattr(LocalPositionKF, "fuse_baro", lambda self, alt: fused.append(alt))
    bench = ModuleBench(LocalPositionEstimatorModule)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude())
    step(bench, pressure=0.0)
    step(bench, pressure=89874.6)
    assert fused == [pytest.approx(1000.0, abs=1.0)]


def test_the_land_detector_is_fused_only_landed_and_at_rest(monkeypatch):
    fused = []
    monkeypatch.setattr(LocalPositionKF, "fuse_land", lambda self: fused.append(True))
    bench = ModuleBench(LocalPositionEstimatorModule)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude())
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=True, at_rest=False))
    step(bench)
    assert fused == []
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=True, at_rest=True))
    step(bench)
    assert fused == [True]


def test_a_parameter_change_reaches_the_filter():
    bench = ModuleBench(LocalPositionEstimatorModule)
    assert bench.module.kf.params.lpe_bar_z != 7.0
    bench.set_param("LPE_BAR_Z", 7.0)
    assert bench.module.kf.params.lpe_bar_z == 7.0
