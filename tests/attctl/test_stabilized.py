"""Stabilized-mode setpoints from sticks, rattitude, and the RotorS roll/pitch/yaw-rate/thrust command."""

import math

import pytest

from stack.attctl.rotors_joy import JoyMapping, RollPitchYawrateThrust
from stack.attctl.stabilized import StabilizedAttitudeSetpoint, rattitude_uses_rate_control, rotors_attitude_setpoint
from stack.mathlib import quaternion as quat

DT = 0.004
TILT_MAX = math.radians(35.0)


def flying(params=None) -> StabilizedAttitudeSetpoint:
    """A generator armed long ago and in the air, with its thrust slews settled."""
    gen = StabilizedAttitudeSetpoint(params)
    for _ in range(10000):
        gen.update_throttle_limits(DT, landed=False, armed=True, now_us=100_000_000, armed_time_us=0)
    return gen


def test_centred_sticks_hold_level_at_the_current_heading_with_hover_thrust():
    gen = flying()
    q = quat.from_euler(0.1, -0.05, 1.2)
    sp = gen.generate(q, 0.0, 0.0, 0.0, 0.0, DT)
    assert sp.q_d == pytest.approx(quat.from_euler(0.0, 0.0, 1.2), abs=1e-12)
    assert sp.yaw_sp_move_rate == 0.0
    assert sp.thrust_body == pytest.approx((0.0, 0.0, -0.5))


def test_stick_tilt_directions_and_norm_limit():
    gen = flying()
    roll_right = gen.generate(quat.IDENTITY, 1.0, 0.0, 0.0, 0.0, DT).q_d
    assert quat.to_euler(roll_right) == pytest.approx((TILT_MAX, 0.0, 0.0), abs=1e-12)
    forward = gen.generate(quat.IDENTITY, 0.0, 1.0, 0.0, 0.0, DT).q_d
    assert quat.to_euler(forward) == pytest.approx((0.0, -TILT_MAX, 0.0), abs=1e-12)  # nose down
    diagonal = gen.generate(quat.IDENTITY, 1.0, 1.0, 0.0, 0.0, DT).q_d
    assert quat.angle_between(diagonal, quat.IDENTITY) == pytest.approx(TILT_MAX)
    # The thrust axis leans toward the stick: right and forward.
    thrust_dir = quat.rotate(diagonal, (0.0, 0.0, -1.0))
    assert thrust_dir[0] > 0.0 and thrust_dir[1] > 0.0
    assert thrust_dir[0] == pytest.approx(thrust_dir[1])


def test_tilt_filter_time_constant():
    gen = flying({"MC_MAN_TILT_TAU": 0.2})
    first = gen.generate(quat.IDENTITY, 1.0, 0.0, 0.0, 0.0, DT).q_d
    assert quat.to_euler(first)[0] == pytest.approx(TILT_MAX * DT / (DT + 0.2))


def test_yaw_stick_integrates_and_holds_when_centred():
    gen = flying()
    q = quat.IDENTITY
    sp = gen.generate(q, 0.0, 0.0, 0.0, 0.0, DT)
    for _ in range(250):  # 1 s at full right yaw
        sp = gen.generate(q, 0.0, 0.0, 1.0, 0.0, DT)
    assert sp.yaw_sp_move_rate == pytest.approx(math.radians(150.0))
    assert quat.yaw(sp.q_d) == pytest.approx(math.radians(150.0))
    # Released: the heading is held even while the vehicle's own yaw wanders.
    for k in range(100):
        sp = gen.generate(quat.from_axis_angle((0.0, 0.0, 1.0), 0.01 * k), 0.0, 0.0, 0.0, 0.0, DT)
    assert sp.yaw_sp_move_rate == 0.0
    assert quat.yaw(sp.q_d) == pytest.approx(math.radians(150.0))


def test_heading_restarts_from_current_yaw_on_arming_gesture_and_reset():
    gen = flying()
    gen.generate(quat.IDENTITY, 0.0, 0.0, 1.0, 0.0, DT)
    q = quat.from_axis_angle((0.0, 0.0, 1.0), -2.0)
    assert quat.yaw(gen.generate(q, 0.0, 0.0, 0.0, -1.0, DT).q_d) == pytest.approx(-2.0)
    gen.generate(quat.IDENTITY, 0.0, 0.0, 1.0, 0.0, DT)
    gen.reset()
    assert quat.yaw(gen.generate(q, 0.0, 0.0, 0.0, 0.0, DT).q_d) == pytest.approx(-2.0)
    airmode = flying({"MC_AIRMODE": 2})
    airmode.generate(quat.IDENTITY, 0.0, 0.0, 0.0, 0.0, DT)
    assert quat.yaw(airmode.generate(q, 0.0, 0.0, 0.0, -1.0, DT).q_d) == pytest.approx(0.0)


def test_heading_reset_shifts_the_held_heading():
    gen = flying()
    gen.generate(quat.IDENTITY, 0.0, 0.0, 0.0, 0.0, DT)
    gen.adapt_to_heading_reset(0.3)
    assert quat.yaw(gen.generate(quat.IDENTITY, 0.0, 0.0, 0.0, 0.0, DT).q_d) == pytest.approx(0.3)


def test_throttle_curves():
    gen = flying()
    assert gen.throttle_curve(-1.0) == pytest.approx(0.08)
    assert gen.throttle_curve(0.0) == pytest.approx(0.5)
    assert gen.throttle_curve(1.0) == pytest.approx(1.0)
    assert gen.throttle_curve(-0.5) == pytest.approx(0.29)
    gen.set_hover_thrust_estimate(0.3)
    for _ in range(5000):  # 0.05 /s: 4 s to move 0.2
        gen.update_throttle_limits(DT, False, True, 100_000_000, 0)
    assert gen.throttle_curve(0.0) == pytest.approx(0.3)
    linear = flying({"MPC_THR_CURVE": 1})
    linear.set_hover_thrust_estimate(0.3)
    assert linear.throttle_curve(0.0) == pytest.approx((0.08 + 1.0) / 2.0)


def test_minimum_thrust_slews_down_on_the_ground():
    gen = flying()
    for _ in range(250):
        gen.update_throttle_limits(DT, landed=True, armed=True, now_us=100_000_000, armed_time_us=0)
    assert gen.throttle_curve(-1.0) == pytest.approx(0.08 - 0.05 * 1.0)


def test_spool_up_holds_thrust_at_zero_then_ramps_at_half_per_second():
    gen = StabilizedAttitudeSetpoint()
    armed_at = 5_000_000
    t = armed_at
    while t <= armed_at + 1_000_000:  # COM_SPOOLUP_TIME
        gen.update_throttle_limits(DT, True, True, t, armed_at)
        t += 4000
    assert gen.throttle_curve(1.0) == 0.0
    for _ in range(250):  # one more second
        gen.update_throttle_limits(DT, True, True, t, armed_at)
        t += 4000
    assert gen.throttle_curve(1.0) == pytest.approx(0.5, abs=0.003)
    gen.update_throttle_limits(DT, True, False, t, armed_at)
    assert gen.throttle_curve(1.0) == 0.0


def test_rattitude_switches_to_rates_beyond_the_threshold():
    assert not rattitude_uses_rate_control(0.79, -0.79)
    assert rattitude_uses_rate_control(0.81, 0.0)
    assert rattitude_uses_rate_control(0.0, -0.81)
    assert rattitude_uses_rate_control(0.5, 0.0, threshold=0.4)


def test_rotors_command_keeps_heading_and_converts_to_ned():
    q = quat.from_euler(0.2, 0.1, 0.7)
    level = rotors_attitude_setpoint(quat.yaw(q), RollPitchYawrateThrust(0.0, 0.0, 0.0, 5.0), 20.0)
    assert level.q_d == pytest.approx(quat.from_euler(0.0, 0.0, 0.7), abs=1e-12)
    assert level.thrust_body == pytest.approx((0.0, 0.0, -0.25))
    # Pitch + is nose up in the stack's frames: the thrust leans backwards (south).
    back = rotors_attitude_setpoint(0.0, RollPitchYawrateThrust(0.0, 0.3, 0.0, 10.0), 20.0)
    assert quat.to_euler(back.q_d) == pytest.approx((0.0, 0.3, 0.0))
    assert quat.rotate(back.q_d, (0.0, 0.0, -1.0))[0] == pytest.approx(-math.sin(0.3))
    # Positive roll is right side down: the thrust leans right (east).
    right = rotors_attitude_setpoint(0.0, RollPitchYawrateThrust(0.3, 0.0, 0.0, 10.0), 20.0)
    assert quat.rotate(right.q_d, (0.0, 0.0, -1.0))[1] == pytest.approx(math.sin(0.3))
    # The yaw rate is the feed-forward about NED down; thrust is clipped to [0, 1].
    spin = rotors_attitude_setpoint(0.0, RollPitchYawrateThrust(0.0, 0.0, 0.5, 30.0), 20.0)
    assert spin.yaw_sp_move_rate == 0.5
    assert spin.thrust_body == (0.0, 0.0, -1.0)


def test_rotors_roll_then_pitch_order():
    # R = Rz·Rx·Ry: the pitch rotation is about the already-rolled y axis.
    sp = rotors_attitude_setpoint(0.0, RollPitchYawrateThrust(0.4, 0.3, 0.0, 1.0), 1.0)
    expected = quat.mul(quat.from_axis_angle((1.0, 0.0, 0.0), 0.4), quat.from_axis_angle((0.0, 1.0, 0.0), 0.3))
    assert sp.q_d == pytest.approx(expected, abs=1e-12)


def test_joy_mapping_is_joy_cpps_scaling_in_the_stacks_frames():
    joy = JoyMapping()
    full = joy.command(roll=1.0, pitch=1.0, yaw=-1.0, throttle=1.0)  # right, forward, anticlockwise, full
    assert full == pytest.approx((math.radians(10.0), -math.radians(10.0), -math.radians(45.0), 30.0))
    assert joy.command(0.0, 0.0, 0.0, 0.0).thrust == pytest.approx(15.0)  # joy.cpp: (axis2 + 1)·30/2
    assert joy.command(0.0, 0.0, 0.0, -1.0).thrust == 0.0
    assert joy.command(5.0, -5.0, 0.0, 9.0) == joy.command(1.0, -1.0, 0.0, 1.0)  # sticks clipped to ±1
    assert joy.command(math.nan, math.inf, math.nan, math.nan) == (0.0, 0.0, 0.0, 0.0)  # not finite: centred, idle
    scaled = JoyMapping({"RJOY_ROLL_MAX": 20.0, "RJOY_THR_MAX": 10.0}).command(0.5, 0.0, 0.0, 1.0)
    assert scaled.roll == pytest.approx(math.radians(10.0)) and scaled.thrust == pytest.approx(10.0)
