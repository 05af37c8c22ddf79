"""The mc_hover_thrust_estimator module on a bench: when it estimates, what it feeds the estimator and what it
publishes (PX4 src/modules/mc_hover_thrust_estimator/MulticopterHoverThrustEstimator.cpp)."""

import math

import pytest

from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleLocalPositionSetpoint
from stack.msg.system import ActuatorArmed, VehicleLandDetected
from stack.posctl.hte_module import HoverThrustEstimatorModule
from tests.support.bench import ModuleBench

DT = 0.02


def step(bench: ModuleBench, az=0.0, v_z_valid=True):
    bench.run(VehicleLocalPosition(timestamp_sample=bench.now + round(DT * 1e6), v_z_valid=v_z_valid, az=az), DT)
    return bench.sent(ORB_ID.hover_thrust_estimate)[-1]


def hovering(**params) -> ModuleBench:
    bench = ModuleBench(HoverThrustEstimatorModule, params)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False))
    bench.put(ORB_ID.vehicle_local_position_setpoint, VehicleLocalPositionSetpoint(thrust=(0.0, 0.0, -0.5)))
    return bench


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(HoverThrustEstimatorModule)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_local_position_setpoint, ORB_ID.vehicle_land_detected, ORB_ID.actuator_armed)
    }
    assert set(bench.outputs) == {(ORB_ID.hover_thrust_estimate.name, 0)}


def test_publishes_each_sample_stamped_with_it_invalid_until_armed_and_in_air():
    bench = ModuleBench(HoverThrustEstimatorModule)
    estimate = step(bench)
    assert estimate.timestamp_sample == bench.now and math.isnan(estimate.hover_thrust) and not estimate.valid
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    assert math.isnan(step(bench).hover_thrust)  # no land detector yet: not known to be in the air
    flying = hovering()
    step(flying)
    assert step(flying).hover_thrust == pytest.approx(0.5, abs=0.05)


def test_without_a_vertical_velocity_the_acceleration_is_not_fused():
    bench = hovering()
    step(bench)
    assert math.isnan(step(bench, v_z_valid=False).hover_thrust)


def test_learns_the_thrust_that_holds_altitude_and_starts_from_mpc_thr_hover():
    bench = hovering(MPC_THR_HOVER=0.5)
    bench.put(ORB_ID.vehicle_local_position_setpoint, VehicleLocalPositionSetpoint(thrust=(0.0, 0.0, -0.6)))
    for _ in range(500):
        estimate = step(bench)  # 0.6 holds altitude (no vertical acceleration): the hover thrust is 0.6
    assert estimate.hover_thrust == pytest.approx(0.6, abs=0.02) and estimate.valid
    bench.set_param("MPC_THR_HOVER", 0.3)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=False))
    step(bench)  # disarmed: back to MPC_THR_HOVER
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    bench.put(ORB_ID.vehicle_local_position_setpoint, VehicleLocalPositionSetpoint(thrust=(0.0, 0.0, -0.3)))
    step(bench)
    assert step(bench).hover_thrust == pytest.approx(0.3, abs=0.01)
