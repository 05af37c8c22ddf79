"""Fuzz the controllers' inputs: any estimate, any setpoint (NaN, ±inf, huge), any yaw. Nothing raises, and what
goes to the next loop is finite, or NaN only where that loop reads NaN as "not controlled"."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from stack.attctl.attitude_control import AttitudeControl
from stack.attctl.rate_control import RateControl
from stack.mixer.allocation import ControlAllocator
from stack.posctl.position_control import PositionControl, failsafe_setpoint
from tests.fuzz.strategies import FUZZ, all_finite, finite_or_nan, nasty_float, quat, vec3


@FUZZ
@given(
    pos=vec3, vel=vec3, vel_dot=vec3, yaw=nasty_float,
    sp_pos=vec3, sp_vel=vec3, sp_acc=vec3, sp_yaw=nasty_float, sp_yawspeed=nasty_float,
    hover=nasty_float, dt=nasty_float,
)
def test_position_control_takes_any_state_and_setpoint(pos, vel, vel_dot, yaw, sp_pos, sp_vel, sp_acc, sp_yaw,
                                                       sp_yawspeed, hover, dt):
    control = PositionControl()
    control.update_hover_thrust(hover)
    control.set_state(pos, vel, vel_dot, yaw)
    control.set_setpoint(sp_pos, sp_vel, sp_acc, sp_yaw, sp_yawspeed)
    executed = control.update(dt)
    if not executed:
        fs = failsafe_setpoint(vel, land_speed=0.7)
        control.set_setpoint(fs.position, fs.velocity, fs.acceleration, math.nan, math.nan)
        executed = control.update(0.02)
    q_d, thrust, yawspeed = control.attitude_setpoint()
    setpoint = control.local_position_setpoint()
    assert math.isfinite(setpoint.yaw) and math.isfinite(yawspeed)
    # not executable even as the failsafe (no usable estimate at all): no setpoint, which the caller drops
    assert (all_finite(q_d) and all_finite(thrust)) or not executed
    assert all_finite(control.velocity_integral)


@FUZZ
@given(q=quat, q_sp=quat, yawspeed=nasty_float)
def test_attitude_control_takes_any_attitude_and_setpoint(q, q_sp, yawspeed):
    control = AttitudeControl()
    control.set_attitude_setpoint(q_sp, yawspeed)
    rates = control.update(q)
    assert all(finite_or_nan(r) for r in rates)
    assert all_finite(rates) or not (all_finite(q) and all_finite(q_sp))


@FUZZ
@given(rate=vec3, rate_sp=vec3, accel=vec3, dt=nasty_float, landed=st.booleans())
def test_rate_control_takes_any_rate_and_setpoint(rate, rate_sp, accel, dt, landed):
    control = RateControl()
    for _ in range(2):
        torque = control.update(rate, rate_sp, accel, dt, landed)
        assert all_finite(torque)
    assert all_finite(control.integral)


@FUZZ
@given(torque=vec3, thrust=vec3, airmode=st.sampled_from([0, 1, 2]))
def test_the_allocator_takes_any_torque_and_thrust(torque, thrust, airmode):
    allocator = ControlAllocator.from_params({"MC_AIRMODE": airmode})
    motors = allocator.allocate(torque, thrust).motors
    assert all(0.0 <= m <= 1.0 for m in motors)
