"""The control_allocator module on a multirotor, on a bench: what arms the motors, what it publishes and stamps,
parameter changes rebuilding the allocation (PX4 src/modules/control_allocator/ControlAllocator.cpp)."""

import math

import pytest

from stack.mixer.module import ControlAllocatorModule
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint, VehicleTorqueSetpoint
from stack.msg.system import ActuatorArmed
from tests.support.bench import ModuleBench

QUAD_X = {"CA_ROTOR_COUNT": 4} | {
    f"CA_ROTOR{i}_P{axis}": v
    for i, xy in enumerate(((1, 1), (-1, -1), (1, -1), (-1, 1)))
    for axis, v in zip("XY", xy, strict=True)
}


def step(bench: ModuleBench, torque=(0.0, 0.0, 0.0), thrust=-0.5, sample=4321):
    bench.put(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(xyz=(0.0, 0.0, thrust)))
    bench.run(VehicleTorqueSetpoint(timestamp_sample=sample, xyz=torque), 0.004)
    return bench.sent(ORB_ID.actuator_motors)[-1]


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(ControlAllocatorModule, QUAD_X)
    assert set(bench.inputs) == {
        (t.name, 0) for t in (ORB_ID.vehicle_thrust_setpoint, ORB_ID.actuator_armed, ORB_ID.vehicle_land_detected)
    }
    assert set(bench.outputs) == {
        (t.name, 0)
        for t in (ORB_ID.actuator_motors, ORB_ID.actuator_outputs, ORB_ID.actuator_outputs_sim,
                  ORB_ID.control_allocator_status, ORB_ID.actuator_servos)
    }


def test_motors_stopped_unless_armed_and_neither_killed_nor_locked_down():
    bench = ModuleBench(ControlAllocatorModule, QUAD_X)
    assert all(math.isnan(v) for v in step(bench).control)
    assert bench.sent(ORB_ID.actuator_outputs_sim)[-1].output == (0.0,) * 16
    for stop in (dict(kill=True), dict(lockdown=True)):
        bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True, **stop))
        assert all(math.isnan(v) for v in step(bench).control)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    motors = step(bench)
    assert motors.control[:4] == pytest.approx((0.5,) * 4) and all(math.isnan(v) for v in motors.control[4:])
    assert bench.sent(ORB_ID.actuator_outputs_sim)[-1].noutputs == 4
    assert bench.sent(ORB_ID.actuator_servos) == []


def test_stamped_with_the_torque_setpoints_sample_and_nan_read_as_zero():
    bench = ModuleBench(ControlAllocatorModule, QUAD_X)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    motors = step(bench, torque=(math.nan, 0.0, 0.0), thrust=math.nan, sample=99)
    assert motors.timestamp_sample == 99
    assert motors.control[:4] == pytest.approx(step(bench, thrust=0.0).control[:4])


def test_unreachable_torque_is_reported_to_the_rate_loop():
    bench = ModuleBench(ControlAllocatorModule, QUAD_X)
    step(bench, torque=(5.0, 0.0, 0.0))
    status = bench.sent(ORB_ID.control_allocator_status)[-1]
    assert not status.torque_setpoint_achieved and status.unallocated_torque[0] > 0.0


def test_a_geometry_change_rebuilds_the_allocation():
    bench = ModuleBench(ControlAllocatorModule, QUAD_X)
    bench.set_param("CA_ROTOR_COUNT", 2)
    step(bench)
    assert bench.module.allocator.num_motors == 2
    assert bench.sent(ORB_ID.actuator_outputs)[-1].noutputs == 2


def test_no_rotors_is_refused_at_build():
    with pytest.raises(ValueError, match="CA_ROTOR_COUNT"):
        ModuleBench(ControlAllocatorModule)
