"""The mc_att_control module on a bench: which setpoint each mode flies and what it publishes
(PX4 src/modules/mc_att_control/mc_att_control_main.cpp)."""

import math

import pytest

from stack.attctl.att_module import MulticopterAttitudeControl
from stack.attctl.attitude_control import AttitudeControl
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import ManualControlSetpoint, VehicleAttitudeSetpoint
from stack.msg.system import VehicleControlMode
from tests.support.bench import ModuleBench

DT = 0.004
ATTITUDE = VehicleControlMode(flag_armed=True, flag_control_attitude_enabled=True, flag_control_rates_enabled=True)
ACRO = VehicleControlMode(flag_armed=True, flag_control_manual_enabled=True, flag_control_rates_enabled=True)


def step(bench: ModuleBench, roll=0.0, **fields) -> None:
    bench.run(VehicleAttitude(timestamp_sample=bench.now, q=quat.from_euler(roll, 0.0, 0.0), **fields), DT)


def test_flies_the_attitude_setpoint_on_the_bus_with_its_thrust():
    bench = ModuleBench(MulticopterAttitudeControl, {"MC_ROLL_P": 4.0})
    bench.put(ORB_ID.vehicle_control_mode, ATTITUDE)
    bench.put(ORB_ID.vehicle_attitude_setpoint,
              VehicleAttitudeSetpoint(q_d=quat.from_euler(0.1, 0.0, 0.0), thrust_body=(0.0, 0.0, -0.4)))
    step(bench)
    rates = bench.sent(ORB_ID.vehicle_rates_setpoint)[-1]
    assert rates.roll == pytest.approx(0.4, rel=0.01) and rates.thrust_body == (0.0, 0.0, -0.4)
    assert bench.sent(ORB_ID.vehicle_attitude_setpoint) == []  # not its own setpoint: not published again
    bench.set_param("MC_ROLL_P", 2.0)
    step(bench)
    assert bench.sent(ORB_ID.vehicle_rates_setpoint)[-1].roll == pytest.approx(0.2, rel=0.01)


def test_silent_without_attitude_or_acro_control_and_on_a_nan_setpoint():
    bench = ModuleBench(MulticopterAttitudeControl)
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=quat.from_euler(0.1, 0.0, 0.0)))
    step(bench)  # no mode yet
    bench.put(ORB_ID.vehicle_control_mode, VehicleControlMode(flag_armed=True, flag_control_rates_enabled=True))
    step(bench)  # offboard rates: another module's
    bench.put(ORB_ID.vehicle_control_mode, ATTITUDE)
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint(q_d=(math.nan, 0.0, 0.0, 0.0)))
    step(bench)
    assert bench.sent(ORB_ID.vehicle_rates_setpoint) == []


def test_acro_maps_the_sticks_to_rates_and_thrust():
    bench = ModuleBench(MulticopterAttitudeControl, {"MC_ACRO_R_MAX": 90.0, "MC_ACRO_EXPO": 0.0,
                                                     "MC_ACRO_SUPEXPO": 0.0})
    bench.put(ORB_ID.vehicle_control_mode, ACRO)
    bench.put(ORB_ID.manual_control_setpoint, ManualControlSetpoint(valid=True, roll=1.0, throttle=1.0))
    step(bench)
    rates = bench.sent(ORB_ID.vehicle_rates_setpoint)[-1]
    assert rates.roll == pytest.approx(math.pi / 2) and rates.thrust_body == (0.0, 0.0, -1.0)
    bench.set_param("MC_ACRO_R_MAX", 45.0)
    step(bench)
    assert bench.sent(ORB_ID.vehicle_rates_setpoint)[-1].roll == pytest.approx(math.pi / 4)


def test_stabilized_publishes_the_stick_setpoint_it_flies():
    bench = ModuleBench(MulticopterAttitudeControl)
    bench.put(ORB_ID.vehicle_control_mode, VehicleControlMode(
        flag_armed=True, flag_control_manual_enabled=True, flag_control_attitude_enabled=True,
        flag_control_rates_enabled=True))
    bench.put(ORB_ID.manual_control_setpoint, ManualControlSetpoint(valid=True, roll=1.0, throttle=0.0))
    step(bench)
    sp = bench.sent(ORB_ID.vehicle_attitude_setpoint)[-1]
    assert quat.to_euler(sp.q_d)[0] > 0.1
    assert bench.sent(ORB_ID.vehicle_rates_setpoint)[-1].roll > 0.0


def test_an_estimator_reset_reaches_the_controller_once(monkeypatch):
    bench = ModuleBench(MulticopterAttitudeControl)
    bench.put(ORB_ID.vehicle_control_mode, ATTITUDE)
    bench.put(ORB_ID.vehicle_attitude_setpoint, VehicleAttitudeSetpoint())
    resets = []
    monkeypatch.setattr(AttitudeControl, "adapt_to_reset", lambda self, delta_q: resets.append(delta_q))
    delta = quat.from_euler(0.0, 0.0, 0.5)
    step(bench)
    step(bench, quat_reset_counter=1, delta_q_reset=delta)
    step(bench, quat_reset_counter=1, delta_q_reset=delta)
    assert resets == [delta]
