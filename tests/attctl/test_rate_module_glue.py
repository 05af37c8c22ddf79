"""The mc_rate_control module on a bench: when it runs, what it publishes and stamps, and what reaches RateControl
(PX4 src/modules/mc_rate_control/MulticopterRateControl.cpp)."""

import pytest

from stack.attctl.rate_module import MulticopterRateControl
from stack.msg.actuators import ControlAllocatorStatus
from stack.msg.estimation import VehicleAngularVelocity
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleRatesSetpoint
from stack.msg.system import VehicleControlMode, VehicleLandDetected
from tests.support.bench import ModuleBench

DT = 0.001
RATES = VehicleControlMode(flag_armed=True, flag_control_rates_enabled=True)
FLYING = VehicleLandDetected(landed=False, maybe_landed=False)


def flying(**params) -> ModuleBench:
    bench = ModuleBench(MulticopterRateControl, {"MC_YAW_TQ_CUTOFF": 0.0, **params})
    bench.put(ORB_ID.vehicle_control_mode, RATES)
    bench.put(ORB_ID.vehicle_land_detected, FLYING)
    return bench


def step(bench: ModuleBench, xyz=(0.0, 0.0, 0.0), sample=None) -> None:
    sample = bench.now if sample is None else sample
    bench.run(VehicleAngularVelocity(timestamp_sample=sample, xyz=xyz), DT)


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(MulticopterRateControl)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_rates_setpoint, ORB_ID.control_allocator_status, ORB_ID.vehicle_control_mode,
                  ORB_ID.vehicle_land_detected)
    }
    assert set(bench.outputs) == {
        (t.name, 0) for t in (ORB_ID.vehicle_thrust_setpoint, ORB_ID.vehicle_torque_setpoint, ORB_ID.rate_ctrl_status)
    }


def test_silent_without_a_mode_with_rates_off_or_without_a_setpoint():
    bench = ModuleBench(MulticopterRateControl)
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(bench)
    bench.put(ORB_ID.vehicle_control_mode, VehicleControlMode(flag_armed=True))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_torque_setpoint) == []
    no_setpoint = flying()
    step(no_setpoint)
    assert no_setpoint.sent(ORB_ID.vehicle_torque_setpoint) == []


def test_publishes_thrust_torque_and_status_stamped_with_the_gyro_sample():
    bench = flying(MC_ROLLRATE_P=0.2, MC_ROLLRATE_K=1.0, MC_ROLLRATE_D=0.0, MC_ROLLRATE_FF=0.0)
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0, thrust_body=(0.0, 0.0, -0.6)))
    step(bench, sample=777)
    torque = bench.sent(ORB_ID.vehicle_torque_setpoint)[-1]
    thrust = bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1]
    assert torque.timestamp_sample == thrust.timestamp_sample == 777
    assert torque.xyz[0] == pytest.approx(0.2, rel=0.02)  # P on a 1 rad/s error (plus one step of I)
    assert thrust.xyz == (0.0, 0.0, -0.6)
    status = bench.sent(ORB_ID.rate_ctrl_status)[-1]
    assert status.rollspeed_integ == bench.module.control.integral[0] > 0.0


def test_a_nan_thrust_is_sent_as_zero():
    bench = flying()
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(thrust_body=(float("nan"), 0.0, -0.5)))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == (0.0, 0.0, -0.5)


def test_a_gain_change_reaches_the_controller():
    bench = flying(MC_ROLLRATE_D=0.0, MC_ROLLRATE_I=0.0)
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(bench)
    before = bench.sent(ORB_ID.vehicle_torque_setpoint)[-1].xyz[0]
    bench.set_param("MC_ROLLRATE_P", 2 * float(bench.params["MC_ROLLRATE_P"]))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_torque_setpoint)[-1].xyz[0] == pytest.approx(2 * before)


def test_integrator_reset_when_disarmed_or_asked_and_held_on_the_ground():
    bench = flying()
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(bench)
    assert bench.module.control.integral[0] > 0.0
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0, reset_integral=True))
    step(bench)
    first_step = bench.sent(ORB_ID.rate_ctrl_status)[0].rollspeed_integ
    assert bench.module.control.integral[0] == pytest.approx(first_step)  # restarted: one step's worth again
    landed = flying()
    landed.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False, maybe_landed=True))
    landed.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(landed)
    assert landed.module.control.integral[0] == 0.0
    disarmed = flying()
    disarmed.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(disarmed)
    disarmed.put(ORB_ID.vehicle_control_mode, VehicleControlMode(flag_control_rates_enabled=True))
    disarmed.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint())
    step(disarmed)
    assert disarmed.module.control.integral == (0.0, 0.0, 0.0)


def test_the_allocators_saturation_holds_the_integrator():
    bench = flying()
    bench.put(ORB_ID.control_allocator_status,
              ControlAllocatorStatus(torque_setpoint_achieved=False, unallocated_torque=(0.5, 0.0, 0.0)))
    bench.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=1.0))
    step(bench)
    assert bench.module.control.integral[0] == 0.0
