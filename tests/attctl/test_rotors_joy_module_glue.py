"""The rotors_joy_interface module on a bench: it publishes RotorS' command only in the RotorS mode with valid
sticks, stamped with the sticks' sample (RotorS rotors_joy_interface/src/joy.cpp)."""

import math

import pytest

from stack.attctl.rotors_joy_module import RotorsJoyInterface
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleControlMode
from tests.support.bench import ModuleBench

RPYT = VehicleControlMode(flag_armed=True, flag_control_rpyt_enabled=True)
STICKS = ManualControlSetpoint(timestamp_sample=1234, valid=True, roll=0.5, pitch=1.0, yaw=-1.0, throttle=0.0)


def test_reads_the_sticks_and_mode_and_writes_the_rotors_command():
    bench = ModuleBench(RotorsJoyInterface)
    assert set(bench.inputs) == {(ORB_ID.manual_control_setpoint.name, 0), (ORB_ID.vehicle_control_mode.name, 0)}
    assert set(bench.outputs) == {(ORB_ID.roll_pitch_yawrate_thrust_setpoint.name, 0)}


def test_maps_the_sticks_in_the_rotors_mode():
    bench = ModuleBench(RotorsJoyInterface, {"RJOY_ROLL_MAX": 30.0, "RJOY_PITCH_MAX": 20.0, "RJOY_YAWRATE_MAX": 90.0,
                                             "RJOY_THR_MAX": 30.0})
    bench.put(ORB_ID.vehicle_control_mode, RPYT)
    bench.put(ORB_ID.manual_control_setpoint, STICKS)
    bench.run(None, 0.01)
    sp = bench.sent(ORB_ID.roll_pitch_yawrate_thrust_setpoint)[-1]
    assert sp.timestamp_sample == 1234
    assert (sp.roll, sp.pitch, sp.yaw_rate, sp.thrust) == pytest.approx(
        (math.radians(15.0), -math.radians(20.0), -math.pi / 2, 15.0))
    bench.set_param("RJOY_THR_MAX", 40.0)
    bench.run(None, 0.01)  # the same sticks again: the timer keeps publishing them
    assert bench.sent(ORB_ID.roll_pitch_yawrate_thrust_setpoint)[-1].thrust == pytest.approx(20.0)


def test_silent_outside_the_mode_or_without_valid_sticks():
    bench = ModuleBench(RotorsJoyInterface)
    bench.put(ORB_ID.manual_control_setpoint, STICKS)
    bench.run(None, 0.01)  # no mode yet
    bench.put(ORB_ID.vehicle_control_mode, VehicleControlMode(flag_armed=True, flag_control_attitude_enabled=True))
    bench.run(None, 0.01)
    bench.put(ORB_ID.vehicle_control_mode, RPYT)
    bench.put(ORB_ID.manual_control_setpoint, ManualControlSetpoint(valid=False, roll=1.0))
    bench.run(None, 0.01)
    assert bench.sent(ORB_ID.roll_pitch_yawrate_thrust_setpoint) == []
