"""The roll_pitch_yawrate_thrust_controller module on a bench: the command each mode follows, what stops the motors,
what it publishes and stamps, refused commands counted once (RotorS
rotors_control/src/nodes/roll_pitch_yawrate_thrust_controller_node.cpp)."""

import math

import pytest

from stack.attctl.rpyt_module import RollPitchYawrateThrustController
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleAngularVelocity, VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import RollPitchYawrateThrustSetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import ActuatorArmed, VehicleControlMode
from tests.support.bench import ModuleBench

DT = 0.004
RPYT = VehicleControlMode(flag_armed=True, flag_control_rpyt_enabled=True, flag_control_attitude_enabled=True)
ATTITUDE = VehicleControlMode(flag_armed=True, flag_control_attitude_enabled=True, flag_control_rates_enabled=True)


def firefly(mode=RPYT, **params) -> ModuleBench:
    bench = ModuleBench(RollPitchYawrateThrustController, params, {"vehicle": "firefly"})
    bench.put(ORB_ID.vehicle_control_mode, mode)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    return bench


def step(bench: ModuleBench, sample=None) -> None:
    bench.run(VehicleAttitude(timestamp_sample=bench.now if sample is None else sample), DT)


def hover_half(bench: ModuleBench) -> RollPitchYawrateThrustSetpoint:
    return RollPitchYawrateThrustSetpoint(thrust=0.5 * bench.module.control.max_thrust)


def test_needs_a_vehicle_model():
    with pytest.raises(ValueError, match="vehicle"):
        ModuleBench(RollPitchYawrateThrustController)


def test_follows_the_rotors_command_and_publishes_stamped_with_the_attitude_sample():
    bench = firefly()
    bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, hover_half(bench))
    step(bench, sample=2468)
    motors = bench.sent(ORB_ID.actuator_motors)[-1]
    thrust = bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1]
    n = bench.module.control.num_rotors
    assert motors.timestamp_sample == thrust.timestamp_sample == 2468
    assert thrust.xyz == pytest.approx((0.0, 0.0, -0.5))
    assert all(0.0 < u < 1.0 for u in motors.control[:n]) and all(math.isnan(u) for u in motors.control[n:])
    sim = bench.sent(ORB_ID.actuator_outputs_sim)[-1]
    assert sim.noutputs == n and sim.output[:n] == pytest.approx(motors.control[:n])


def test_motors_stop_and_the_command_is_forgotten_when_disarmed_killed_or_terminated():
    for stop in (dict(armed=False), dict(armed=True, kill=True), dict(armed=True, termination=True)):
        bench = firefly()
        bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, hover_half(bench))
        step(bench)
        bench.put(ORB_ID.actuator_armed, ActuatorArmed(**stop))
        step(bench)
        assert all(math.isnan(u) for u in bench.sent(ORB_ID.actuator_motors)[-1].control)
        assert bench.sent(ORB_ID.actuator_outputs_sim)[-1].output == (0.0,) * 16
        bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
        step(bench)  # no new command: the forgotten one is not flown again
        assert bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == (0.0, 0.0, 0.0)


def test_attitude_control_flies_the_attitude_setpoint_and_rates_the_rates_setpoint():
    bench = firefly(ATTITUDE)
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=quat.from_euler(0.1, 0.0, 0.0),
                                                                        thrust_body=(0.0, 0.0, -0.4)))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == pytest.approx((0.0, 0.0, -0.4))
    assert bench.sent(ORB_ID.vehicle_attitude_setpoint) == []  # not its own setpoint
    rates = firefly(VehicleControlMode(flag_armed=True, flag_control_rates_enabled=True))
    rates.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=0.2, thrust_body=(0.0, 0.0, -0.3)))
    step(rates)
    assert rates.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == pytest.approx((0.0, 0.0, -0.3))


def test_a_rotors_command_outside_the_rotors_mode_is_not_followed():
    bench = firefly(ATTITUDE)
    bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, hover_half(bench))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == (0.0, 0.0, 0.0)


def test_a_non_finite_command_is_refused_once_and_the_last_good_one_kept():
    bench = firefly()
    bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, hover_half(bench))
    step(bench)
    bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, RollPitchYawrateThrustSetpoint(roll=math.nan, thrust=1.0))
    step(bench)
    step(bench)
    assert bench.rejected == 1
    assert bench.sent(ORB_ID.vehicle_thrust_setpoint)[-1].xyz == pytest.approx((0.0, 0.0, -0.5))
    rates = firefly(VehicleControlMode(flag_armed=True, flag_control_rates_enabled=True))
    rates.put(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=math.inf))
    step(rates)
    step(rates)  # the same setpoint still the latest: counted once
    assert rates.rejected == 1


def test_a_gain_change_reaches_the_controller():
    bench = firefly(RPYT_ATT_GAIN_X=1.0)
    bench.put(ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity())
    bench.put(ORB_ID.roll_pitch_yawrate_thrust_setpoint, RollPitchYawrateThrustSetpoint(roll=0.2, thrust=5.0))
    step(bench)
    weak = bench.sent(ORB_ID.actuator_motors)[-1].control[:6]
    bench.set_param("RPYT_ATT_GAIN_X", 4.0)
    step(bench)
    strong = bench.sent(ORB_ID.actuator_motors)[-1].control[:6]
    assert max(strong) - min(strong) > max(weak) - min(weak)
