"""The fw_att_control module on a bench: which setpoint each mode flies, what it publishes, and when."""

import math

import pytest

from stack.fw.att_module import FixedwingAttitudeControl
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleAngularVelocity, VehicleAttitude, VehicleLocalPosition
from stack.msg.fixedwing import AirspeedValidated
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import ManualControlSetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import ActuatorArmed, VehicleControlMode, VehicleLandDetected
from tests.support.bench import ModuleBench

DT = 0.004
MANUAL = VehicleControlMode(flag_armed=True, flag_control_manual_enabled=True)
STABILIZED = VehicleControlMode(flag_armed=True, flag_control_manual_enabled=True, flag_control_attitude_enabled=True,
                                flag_control_rates_enabled=True)
ACRO = VehicleControlMode(flag_armed=True, flag_control_manual_enabled=True, flag_control_rates_enabled=True)
AUTO = VehicleControlMode(flag_armed=True, flag_control_auto_enabled=True, flag_control_position_enabled=True,
                          flag_control_altitude_enabled=True, flag_control_climb_rate_enabled=True,
                          flag_control_attitude_enabled=True, flag_control_rates_enabled=True)
POSITION = VehicleControlMode(flag_armed=True, flag_control_manual_enabled=True, flag_control_position_enabled=True,
                              flag_control_altitude_enabled=True, flag_control_climb_rate_enabled=True,
                              flag_control_attitude_enabled=True, flag_control_rates_enabled=True)


def flying(mode: VehicleControlMode, **params) -> ModuleBench:
    bench = ModuleBench(FixedwingAttitudeControl, params)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    bench.put(ORB_ID.vehicle_control_mode, mode)
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False, maybe_landed=False, ground_contact=False))
    bench.put(ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity())
    bench.put(ORB_ID.airspeed_validated, AirspeedValidated(calibrated_airspeed_m_s=15.0))
    return bench


def step(bench: ModuleBench, roll=0.0, pitch=0.0, yaw=0.0) -> None:
    bench.run(VehicleAttitude(timestamp_sample=bench.now, q=quat.from_euler(roll, pitch, yaw)), DT)


def sticks(roll=0.0, pitch=0.0, yaw=0.0, throttle=-1.0) -> ManualControlSetpoint:
    return ManualControlSetpoint(valid=True, roll=roll, pitch=pitch, yaw=yaw, throttle=throttle)


def last(bench: ModuleBench, topic: str):
    return bench.sent(topic)[-1]


def test_disarmed_publishes_zero_torque_and_thrust_and_restarts_the_integrators():
    bench = flying(ACRO)
    bench.put(ORB_ID.manual_control_setpoint, sticks(roll=1.0, throttle=1.0))
    step(bench)
    assert bench.module.control.integrals[0] > 0.0
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=False))
    step(bench)
    assert last(bench, ORB_ID.vehicle_torque_setpoint).xyz == (0.0, 0.0, 0.0)
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == (0.0, 0.0, 0.0)
    assert bench.module.control.integrals == (0.0, 0.0, 0.0, 0.0)


def test_manual_passes_the_sticks_to_the_surfaces_and_the_throttle():
    bench = flying(MANUAL, FW_MAN_R_SC=0.5)
    bench.put(ORB_ID.manual_control_setpoint, sticks(roll=0.6, pitch=0.4, yaw=-0.3, throttle=0.2))
    step(bench, roll=0.5)  # the attitude does not matter
    assert last(bench, ORB_ID.vehicle_torque_setpoint).xyz == pytest.approx((0.3, -0.4, -0.3))
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == pytest.approx((0.6, 0.0, 0.0))
    assert bench.sent(ORB_ID.vehicle_rates_setpoint) == []


def test_stabilized_flies_the_stick_angles_and_publishes_them():
    bench = flying(STABILIZED)
    bench.put(ORB_ID.manual_control_setpoint, sticks(roll=0.5, pitch=-1.0, throttle=0.0))
    step(bench, yaw=1.0)
    sp = last(bench, ORB_ID.vehicle_attitude_setpoint)
    roll, pitch, yaw = quat.to_euler(sp.q_d)
    # Half right roll of FW_MAN_R_MAX 45°, full back stick = nose up FW_MAN_P_MAX 45°, heading kept.
    assert (roll, pitch, yaw) == pytest.approx((math.radians(22.5), math.radians(45.0), 1.0))
    assert sp.thrust_body == pytest.approx((0.5, 0.0, 0.0))
    rates = last(bench, ORB_ID.vehicle_rates_setpoint)
    assert rates.roll > 0.0 and rates.pitch > 0.0
    torque = last(bench, ORB_ID.vehicle_torque_setpoint).xyz
    assert torque[0] > 0.0 and torque[1] > 0.0
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == pytest.approx((0.5, 0.0, 0.0))


def test_acro_flies_the_stick_rates():
    bench = flying(ACRO)
    bench.put(ORB_ID.manual_control_setpoint, sticks(roll=1.0, pitch=1.0, yaw=-1.0, throttle=1.0))
    step(bench)
    rates = last(bench, ORB_ID.vehicle_rates_setpoint)
    assert (rates.roll, rates.pitch, rates.yaw) == pytest.approx((math.pi / 2, -math.pi / 2, -math.pi / 4))
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == (1.0, 0.0, 0.0)


def test_auto_flies_the_position_controllers_setpoint():
    bench = flying(AUTO)
    bench.put(ORB_ID.manual_control_setpoint, sticks(roll=1.0, throttle=1.0))  # ignored outside the stick modes
    bench.put(ORB_ID.vehicle_attitude_setpoint,
              VehicleAttitudeSetpoint(q_d=quat.from_euler(0.2, 0.1, 0.0), thrust_body=(0.6, 0.0, 0.0)))
    step(bench)
    rates = last(bench, ORB_ID.vehicle_rates_setpoint)
    assert (rates.roll, rates.pitch) == pytest.approx((0.5, 0.25), abs=0.02)
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == pytest.approx((0.6, 0.0, 0.0))
    assert all(-1.0 <= v <= 1.0 for v in last(bench, ORB_ID.vehicle_torque_setpoint).xyz)
    # Position mode (manual, with the climb-rate loop) also flies fw_pos_control's setpoint, not the sticks.
    position = flying(POSITION)
    position.put(ORB_ID.manual_control_setpoint, sticks(roll=1.0, throttle=1.0))
    position.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(thrust_body=(0.3, 0.0, 0.0)))
    step(position)
    assert last(position, ORB_ID.vehicle_thrust_setpoint).xyz == pytest.approx((0.3, 0.0, 0.0))
    assert position.sent(ORB_ID.vehicle_attitude_setpoint) == []


def test_the_setpoints_integrator_reset_and_wheel_steering():
    bench = flying(AUTO, FW_W_EN=True)
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(v_xy_valid=True, vx=10.0))
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=quat.from_euler(0.3, 0.0, 0.05)))
    step(bench)
    assert bench.module.control.integrals[0] > 0.0
    bench.put(ORB_ID.vehicle_attitude_setpoint,
              VehicleAttitudeSetpoint(q_d=quat.from_euler(0.0, 0.0, 0.05), fw_control_yaw_wheel=True,
                                      reset_integral=True))
    step(bench)
    assert bench.module.control.integrals[0] == 0.0
    assert last(bench, ORB_ID.vehicle_rates_setpoint).yaw == pytest.approx(0.5)  # heading error 0.05 rad over 0.1 s
    # Outside the auto modes the wheel is not steered.
    stabilized = flying(POSITION, FW_W_EN=True)
    stabilized.put(ORB_ID.vehicle_attitude_setpoint,
                   VehicleAttitudeSetpoint(q_d=quat.from_euler(0.0, 0.0, 0.05), fw_control_yaw_wheel=True))
    step(stabilized)
    assert last(stabilized, ORB_ID.vehicle_rates_setpoint).yaw == 0.0


def test_no_valid_airspeed_flies_on_the_trim_scaling():
    stale = flying(ACRO, FW_AIRSPD_MAX=40.0)
    stale.put(ORB_ID.airspeed_validated, AirspeedValidated(calibrated_airspeed_m_s=30.0))
    stale.now += 2_000_000  # two seconds old
    missing = flying(ACRO, FW_AIRSPD_MAX=40.0)
    missing.put(ORB_ID.airspeed_validated, AirspeedValidated())  # NaN: invalid
    fast = flying(ACRO, FW_AIRSPD_MAX=40.0)
    fast.put(ORB_ID.airspeed_validated, AirspeedValidated(calibrated_airspeed_m_s=30.0))
    torques = []
    for bench in (stale, missing, fast):
        bench.put(ORB_ID.manual_control_setpoint, sticks(roll=0.5))
        step(bench)
        torques.append(last(bench, ORB_ID.vehicle_torque_setpoint).xyz[0])
    assert torques[0] == torques[1]
    assert torques[2] < 0.6 * torques[0]


def test_bad_inputs_are_refused():
    bench = flying(AUTO)
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=(math.nan, 0.0, 0.0, 0.0)))
    step(bench)
    bench.put(ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity(xyz=(math.nan, 0.0, 0.0)))
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint())
    step(bench)
    bench.run(VehicleAttitude(q=(math.inf, 0.0, 0.0, 0.0)), DT)
    assert bench.sent(ORB_ID.vehicle_torque_setpoint) == []
    assert bench.rejected == 3
    manual = flying(MANUAL)
    manual.put(ORB_ID.manual_control_setpoint, sticks(roll=math.nan))
    step(manual)
    assert manual.sent(ORB_ID.vehicle_torque_setpoint) == [] and manual.rejected == 1


def test_rates_from_outside_when_only_the_rate_loop_runs():
    bench = flying(VehicleControlMode(flag_armed=True, flag_control_offboard_enabled=True,
                                      flag_control_rates_enabled=True))
    rates = VehicleRatesSetpoint(roll=0.3, pitch=-0.2, yaw=0.1, thrust_body=(0.4, 0, 0))
    bench.put(ORB_ID.vehicle_rates_setpoint, rates)
    step(bench)
    rates = last(bench, ORB_ID.vehicle_rates_setpoint)
    assert (rates.roll, rates.pitch, rates.yaw) == pytest.approx((0.3, -0.2, 0.1))
    assert last(bench, ORB_ID.vehicle_thrust_setpoint).xyz == pytest.approx((0.4, 0.0, 0.0))
