"""Fixed-wing control allocation (CA_AIRFRAME 1): forward motors and control surfaces, and its outputs."""

import math

import numpy as np
import pytest

from stack.mixer.fixedwing import FixedWingAllocator, fixed_wing_effectiveness, surface_torques
from stack.mixer.module import ControlAllocatorModule
from stack.mixer.output import MotorOutput, servo_outputs
from stack.msg.actuators import ActuatorOutputs
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint, VehicleTorqueSetpoint
from stack.msg.system import ActuatorArmed
from tests.support.bench import ModuleBench

PLANE = {"CA_AIRFRAME": 1, "CA_ROTOR_COUNT": 1, "CA_ROTOR0_PX": 0.3}
"""PX4's SIH airplane (10041_sihsim_airplane): one motor; the default surfaces aileron, elevator, rudder."""


def test_the_default_plane_maps_each_axis_to_its_surface_and_thrust_to_the_motor():
    plane = FixedWingAllocator.from_params(PLANE)
    assert (plane.num_motors, plane.num_surfaces) == (1, 3)
    for axis, surface in ((0, 0), (1, 1), (2, 2)):
        torque = [0.0, 0.0, 0.0]
        torque[axis] = -0.4
        result = plane.allocate(tuple(torque), (0.0, 0.0, 0.0))
        expected = [0.0, 0.0, 0.0]
        expected[surface] = -0.4
        assert result.servos == pytest.approx(expected)
        assert result.motors == (0.0,)
    result = plane.allocate((0.0, 0.0, 0.0), (0.65, 0.0, 0.0))
    assert result.motors == pytest.approx((0.65,)) and result.servos == pytest.approx((0.0, 0.0, 0.0))
    assert result.torque_achieved and result.thrust_achieved


def test_the_motor_thrust_is_normalised_whatever_its_ct():
    # The forward motor's column is CT·(1, 0, 0) for the force; normalising the thrust axis cancels CT, and
    # the CA_ROTOR0_AZ of a multicopter does not apply to it.
    plane = FixedWingAllocator.from_params({**PLANE, "CA_ROTOR0_CT": 6.0, "CA_ROTOR0_AZ": -1.0})
    assert plane.allocate((0.0, 0.0, 0.0), (0.3, 0.0, 0.0)).motors == pytest.approx((0.3,))
    b = fixed_wing_effectiveness({**PLANE, "CA_ROTOR0_CT": 6.0})
    assert b[:, 0] == pytest.approx([0.0, 0.0, 0.0, 6.0, 0.0, 0.0])


def test_commands_are_clipped_and_the_shortfall_reported():
    plane = FixedWingAllocator.from_params(PLANE)
    result = plane.allocate((1.5, -2.0, 0.5), (1.2, 0.0, -0.5))
    assert result.servos == (1.0, -1.0, 0.5) and result.motors == (1.0,)
    assert result.unallocated_torque == pytest.approx((0.5, -1.0, 0.0))
    assert result.unallocated_thrust == pytest.approx((0.2, 0.0, -0.5))  # nothing pushes along z
    assert not result.torque_achieved and not result.thrust_achieved
    assert result.actuator_saturation == (2, 2, -2, 0)
    assert plane.allocate((0.0, 0.0, 0.0), (-0.5, 0.0, 0.0)).motors == (0.0,)  # no reverse thrust


def test_elevons_share_roll_and_pitch_through_the_pseudo_inverse():
    # A flying wing: left elevon (−0.5 roll, +0.5 pitch), right elevon (+0.5, +0.5). The pseudo-inverse of
    # [[−0.5, 0.5], [0.5, 0.5]] is [[−1, 1], [1, 1]]: left = −roll + pitch, right = roll + pitch.
    wing = FixedWingAllocator.from_params({
        **PLANE, "CA_SV_CS_COUNT": 2,
        "CA_SV_CS0_TYPE": 5, "CA_SV_CS0_TRQ_R": -0.5, "CA_SV_CS0_TRQ_P": 0.5, "CA_SV_CS0_TRQ_Y": 0.0,
        "CA_SV_CS1_TYPE": 6, "CA_SV_CS1_TRQ_R": 0.5, "CA_SV_CS1_TRQ_P": 0.5, "CA_SV_CS1_TRQ_Y": 0.0,
    })
    assert wing.allocate((0.2, 0.3, 0.0), (0.5, 0.0, 0.0)).servos == pytest.approx((0.1, 0.5))
    # No surface moves the nose sideways: yaw is left unallocated (its weak row is dropped).
    result = wing.allocate((0.0, 0.0, 0.4), (0.0, 0.0, 0.0))
    assert result.servos == pytest.approx((0.0, 0.0)) and result.unallocated_torque == pytest.approx((0, 0, 0.4))


def test_flaps_and_the_steering_wheel_take_no_torque():
    params = {**PLANE, "CA_SV_CS_COUNT": 4, "CA_SV_CS3_TYPE": 9, "CA_SV_CS3_TRQ_R": 1.0}
    assert surface_torques(params)[3] == pytest.approx([0.0, 0.0, 0.0])
    assert surface_torques({**params, "CA_SV_CS3_TYPE": 16})[3] == pytest.approx([0.0, 0.0, 0.0])
    assert surface_torques({**params, "CA_SV_CS3_TYPE": 12})[3] == pytest.approx([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="CA_SV_CS_COUNT"):
        surface_torques({"CA_SV_CS_COUNT": 9})


def test_a_planes_motor_has_no_idle_and_its_surfaces_centre_when_disarmed():
    plane = MotorOutput(1, idle=False)
    assert plane.update((0.0,), True, 0.004).sim == (0.0,)
    assert plane.update((0.4,), True, 0.004) == ((0.4,), (1400.0,), (pytest.approx(0.4),))
    assert MotorOutput(1).update((0.0,), True, 0.004).sim == (pytest.approx(0.075),)  # a multicopter idles
    assert servo_outputs((0.5, -1.5, math.nan), True) == ((0.5, -1.0, 0.0), (1750.0, 1000.0, 1500.0), (0.5, -1.0, 0.0))
    assert servo_outputs((0.5, -0.5), False) == ((0.0, 0.0), (1500.0, 1500.0), (0.0, 0.0))


def plane_outputs(bench: ModuleBench, torque, throttle) -> ActuatorOutputs:
    bench.put(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(xyz=(throttle, 0.0, 0.0)))
    bench.run(VehicleTorqueSetpoint(xyz=torque), 0.004)
    return bench.sent(ORB_ID.actuator_outputs_sim)[-1]


def test_the_allocator_module_drives_a_plane_in_the_shared_output_convention():
    bench = ModuleBench(ControlAllocatorModule, PLANE)
    disarmed = plane_outputs(bench, (0.3, -0.2, 0.1), 0.7)
    assert disarmed.noutputs == 4 and disarmed.output == (0.0,) * 16
    assert math.isnan(bench.sent(ORB_ID.actuator_motors)[-1].control[0])
    assert bench.sent(ORB_ID.actuator_servos)[-1].control[:3] == (0.0, 0.0, 0.0)
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    armed = plane_outputs(bench, (0.3, -0.2, 0.1), 0.7)
    # throttle, aileron, elevator, rudder
    assert armed.output[:4] == pytest.approx((0.7, 0.3, -0.2, 0.1)) and armed.output[4:] == (0.0,) * 12
    assert bench.sent(ORB_ID.actuator_servos)[-1].control[:3] == pytest.approx((0.3, -0.2, 0.1))
    assert all(math.isnan(v) for v in bench.sent(ORB_ID.actuator_servos)[-1].control[3:])
    assert bench.sent(ORB_ID.actuator_motors)[-1].control[0] == pytest.approx(0.7)
    assert bench.sent(ORB_ID.actuator_outputs)[-1].output[:4] == pytest.approx((1700.0, 1650.0, 1400.0, 1550.0))
    nan = plane_outputs(bench, (math.nan, 0.5, 0.0), math.nan)
    assert nan.output[:4] == pytest.approx((0.0, 0.0, 0.5, 0.0))


def test_the_airframe_parameter_switches_between_multicopter_and_plane():
    quad = {f"CA_ROTOR{i}_P{c}": v for i, (x, y) in enumerate(((1, 1), (-1, -1), (1, -1), (-1, 1)))
            for c, v in (("X", x), ("Y", y))}
    bench = ModuleBench(ControlAllocatorModule, {"CA_ROTOR_COUNT": 4, **quad})
    bench.put(ORB_ID.actuator_armed, ActuatorArmed(armed=True))
    bench.put(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(xyz=(0.0, 0.0, -0.5)))
    bench.run(VehicleTorqueSetpoint(), 0.004)
    assert bench.sent(ORB_ID.actuator_outputs_sim)[-1].noutputs == 4 and bench.sent(ORB_ID.actuator_servos) == []
    hover = bench.sent(ORB_ID.actuator_motors)[-1].control[:4]
    assert hover == pytest.approx((0.5,) * 4)
    for name, value in (("CA_ROTOR_COUNT", 1), ("CA_ROTOR0_PY", 0.0), ("CA_AIRFRAME", 1)):
        bench.set_param(name, value)
    assert plane_outputs(bench, (0.0, 0.1, 0.0), 0.5).output[:4] == pytest.approx((0.5, 0.0, 0.1, 0.0))
    with pytest.raises(ValueError, match="CA_ROTOR_COUNT is 0"):
        ModuleBench(ControlAllocatorModule, {"CA_AIRFRAME": 1})
    assert np.shape(fixed_wing_effectiveness(PLANE)) == (6, 4)
