"""Fuzz RotorS' controller and the commands it takes: any command, setpoint, attitude or body rate (NaN, ±inf,
huge). Nothing raises, the motor commands stay in [0, 1], and a command that is not finite is refused."""

from __future__ import annotations

import math

from hypothesis import given

from stack.airframe.model import load_vehicle
from stack.attctl.rotors_joy import JoyMapping, RollPitchYawrateThrust
from stack.attctl.rpyt_control import RollPitchYawrateThrustControl
from stack.attctl.rpyt_setpoints import command_from_attitude
from tests.fuzz.strategies import FUZZ, all_finite, nasty_float, quat, vec3

FIREFLY = load_vehicle("firefly")


def _in_range(motors: tuple[float, ...]) -> bool:
    return len(motors) == FIREFLY.rotor_count and all(0.0 <= u <= 1.0 for u in motors)


@FUZZ
@given(roll=nasty_float, pitch=nasty_float, yaw_rate=nasty_float, thrust=nasty_float, q=quat, rates=vec3)
def test_the_controller_takes_any_command_attitude_and_rates(roll, pitch, yaw_rate, thrust, q, rates):
    control = RollPitchYawrateThrustControl(FIREFLY)
    command = RollPitchYawrateThrust(roll, pitch, yaw_rate, thrust)
    assert control.set_command(command) == all_finite(command)
    assert _in_range(control.motors(q, rates))
    assert math.isfinite(control.thrust)


@FUZZ
@given(rates_sp=vec3, thrust=nasty_float, q=quat, rates=vec3, acceleration=vec3)
def test_a_rate_command_and_any_acceleration_demand_keep_the_motors_in_range(rates_sp, thrust, q, rates, acceleration):
    control = RollPitchYawrateThrustControl(FIREFLY)
    accepted = control.set_rates_command(rates_sp, thrust)
    assert accepted == (math.isfinite(thrust) and not any(math.isinf(r) for r in rates_sp))
    assert _in_range(control.motors(q, rates))
    if math.isfinite(thrust):
        assert _in_range(control.allocate(acceleration, thrust))


@FUZZ
@given(q=quat, q_d=quat, yaw_ff=nasty_float, thrust=vec3, yaw_p=nasty_float, sticks=quat)
def test_px4_setpoints_and_sticks_make_commands_the_controller_takes_or_refuses(q, q_d, yaw_ff, thrust, yaw_p, sticks):
    control = RollPitchYawrateThrustControl(FIREFLY)
    command = command_from_attitude(q, q_d, yaw_ff, thrust, yaw_p, 36.0)
    assert control.set_command(command) == all_finite(command)
    assert _in_range(control.motors(q, (0.0, 0.0, 0.0)))
    assert all_finite(JoyMapping().command(*sticks))
