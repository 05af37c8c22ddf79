"""ArduPilot input shaping: sqrt_controller and friends, and the stateful target shaper."""

import itertools
import math
import random

import pytest

from stack.attctl.attitude_control import AttitudeControl
from stack.attctl.input_shaping import (
    AttitudeInputShaper,
    AttitudeSetpointShaping,
    ShapedAttitude,
    ang_vel_limit,
    ang_vel_to_euler_rate,
    combine_with_feedforward,
    euler_accel_limit,
    euler_rate_to_ang_vel,
    input_shaping_ang_vel,
    input_shaping_angle,
    inv_sqrt_controller,
    sqrt_controller,
)
from stack.mathlib import quaternion as quat

DT = 0.0025


def test_sqrt_controller_is_continuous_in_value_and_slope_at_the_knee():
    p, a = 6.0, 20.0
    h = 1e-7
    for knee in (a / (p * p), -a / (p * p)):
        assert sqrt_controller(knee - h, p, a, 0.0) == pytest.approx(math.copysign(a / p, knee), abs=1e-5)
        assert sqrt_controller(knee + h, p, a, 0.0) == pytest.approx(math.copysign(a / p, knee), abs=1e-5)
        slope_left = (sqrt_controller(knee, p, a, 0.0) - sqrt_controller(knee - 1e-6, p, a, 0.0)) / 1e-6
        slope_right = (sqrt_controller(knee + 1e-6, p, a, 0.0) - sqrt_controller(knee, p, a, 0.0)) / 1e-6
        assert slope_left == pytest.approx(p, rel=1e-4)
        assert slope_right == pytest.approx(p, rel=1e-4)


def test_sqrt_controller_branches():
    assert sqrt_controller(0.5, 2.0, 0.0, 0.0) == 1.0  # no limit: plain P
    assert sqrt_controller(-2.0, 0.0, 4.0, 0.0) == -4.0  # no P: sqrt(2·a·|e|)
    assert sqrt_controller(0.0, 0.0, 4.0, 0.0) == 0.0
    # Far from zero: a constant deceleration a brings the rate to the linear region.
    assert sqrt_controller(10.0, 1.0, 2.0, 0.0) == pytest.approx(math.sqrt(2 * 2.0 * (10.0 - 1.0)))


def test_sqrt_controller_never_overshoots_in_one_step():
    # P · e = 50 · 0.01 = 0.5, but the error would be crossed in one 10 ms step above 1.0: clamp to |e|/dt.
    assert sqrt_controller(0.01, 50.0, 0.0, 0.0) == pytest.approx(0.5)
    assert sqrt_controller(0.01, 500.0, 0.0, 0.01) == pytest.approx(1.0)
    assert sqrt_controller(-0.01, 500.0, 0.0, 0.01) == pytest.approx(-1.0)


@pytest.mark.parametrize("error", [-3.0, -0.4, -0.01, 0.0, 0.02, 0.3, 5.0])
def test_inv_sqrt_controller_inverts_sqrt_controller(error):
    p, a = 4.5, 7.0
    assert inv_sqrt_controller(sqrt_controller(error, p, a, 0.0), p, a) == pytest.approx(error, abs=1e-12)
    assert inv_sqrt_controller(sqrt_controller(error, p, 0.0, 0.0), p, 0.0) == pytest.approx(error, abs=1e-12)
    if error >= 0.0:
        assert inv_sqrt_controller(sqrt_controller(error, 0.0, a, 0.0), 0.0, a) == pytest.approx(error, abs=1e-12)


def test_input_shaping_ang_vel_limits_the_change_and_applies_the_time_constant():
    assert input_shaping_ang_vel(0.0, 10.0, 100.0, 0.01) == pytest.approx(1.0)
    assert input_shaping_ang_vel(0.0, -10.0, 100.0, 0.01) == pytest.approx(-1.0)
    assert input_shaping_ang_vel(0.0, 10.0, 0.0, 0.01) == 10.0
    # First-order lag with tc = 0.1 s: one 10 ms step covers 10 % of the way.
    assert input_shaping_ang_vel(0.0, 10.0, 0.0, 0.01, 0.1) == pytest.approx(1.0)


def test_input_shaping_angle_respects_max_rate_and_desired_rate():
    assert input_shaping_angle(1.0, 0.15, 0.0, 0.0, DT, max_rate=0.5) == 0.5
    assert input_shaping_angle(0.0, 0.15, 0.0, 0.0, DT, desired_rate=0.3) == pytest.approx(0.3)


def test_euler_rate_and_body_rate_round_trip():
    rng = random.Random(1)
    for _ in range(200):
        euler = (rng.uniform(-3.0, 3.0), rng.uniform(-1.4, 1.4), rng.uniform(-3.0, 3.0))
        rates = (rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5))
        body = euler_rate_to_ang_vel(euler, rates)
        assert ang_vel_to_euler_rate(euler, body) == pytest.approx(rates, abs=1e-9)


def test_euler_rates_match_the_quaternion_kinematics():
    euler = (0.3, -0.4, 1.1)
    rates = (0.2, -0.5, 0.7)
    dt = 1e-6
    q0 = quat.from_euler(*euler)
    q1 = quat.integrate(q0, euler_rate_to_ang_vel(euler, rates), dt)
    moved = quat.to_euler(q1)
    assert [(moved[i] - euler[i]) / dt for i in range(3)] == pytest.approx(list(rates), rel=1e-4)


def test_euler_accel_limit():
    a = (10.0, 10.0, 2.0)
    # Level: pitch limited by yaw/sin(0.1 floor), yaw by the yaw limit itself.
    assert euler_accel_limit((0.0, 0.0, 0.0), a) == pytest.approx((10.0, min(10.0, 2.0 / 0.1), min(100.0, 100.0, 2.0)))
    # Banked 90°: a yaw (Euler) acceleration is body pitch, so it is held to the pitch limit.
    banked = euler_accel_limit((math.pi / 2, 0.0, 0.0), a)
    assert banked[2] == pytest.approx(min(10.0 / 0.1, 10.0 / 1.0, 2.0 / 0.1))
    # Pitched 60° with wings level: yaw is shared with body yaw through cos θ (current ArduPilot; its 2023
    # AC_AttitudeControl::euler_accel_limit had no cos θ and would give 2.0 here).
    assert euler_accel_limit((0.0, math.radians(60.0), 0.0), a)[2] == pytest.approx(2.0 / 0.5)
    assert euler_accel_limit((0.3, 0.2, 0.0), (10.0, 0.0, 2.0)) == (10.0, 0.0, 2.0)


def test_ang_vel_limit_keeps_the_tilt_rate_direction():
    p, q, r = ang_vel_limit((3.0, 4.0, 9.0), 1.0, 1.0, 2.0)
    assert (p, q, r) == pytest.approx((0.6, 0.8, 2.0))
    assert ang_vel_limit((3.0, -4.0, 9.0), 0.0, 1.0, 0.0) == (3.0, -1.0, 9.0)
    assert ang_vel_limit((0.1, 0.2, 0.3), 1.0, 1.0, 1.0) == (0.1, 0.2, 0.3)


def run_roll_step(shaper: AttitudeInputShaper, roll: float, steps: int) -> list[tuple[float, float]]:
    """(target roll angle, target roll rate) after each step, the vehicle following the target exactly."""
    trace = []
    for _ in range(steps):
        out = shaper.input_euler_angle_roll_pitch_yaw(roll, 0.0, 0.0, False, shaper.q_target, DT)
        trace.append((quat.to_euler(out.q_target)[0], shaper.target_rate[0]))
    return trace


def test_shaper_step_respects_rate_and_acceleration_limits_and_does_not_overshoot():
    shaper = AttitudeInputShaper({"ATC_RATE_R_MAX": 90.0})
    shaper.reset(quat.IDENTITY)
    goal = math.radians(30.0)
    trace = run_roll_step(shaper, goal, 800)
    accel_max = math.radians(1100.0)
    rates = [0.0] + [r for _, r in trace]
    assert max(abs(b - a) for a, b in itertools.pairwise(rates)) <= accel_max * DT * (1 + 1e-9)
    assert max(abs(r) for r in rates) <= math.radians(90.0) * (1 + 1e-9)
    assert max(abs(r) for r in rates) == pytest.approx(math.radians(90.0))  # the limit is reached
    angles = [a for a, _ in trace]
    assert max(angles) <= goal + 1e-9
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(angles))  # monotonic approach
    assert angles[-1] == pytest.approx(goal, abs=1e-5)


def test_shaper_time_constant_sets_the_final_approach():
    # Near the goal the sqrt controller is linear with gain 1/ATC_INPUT_TC: the error decays as exp(−t/tc).
    shaper = AttitudeInputShaper({"ATC_INPUT_TC": 0.2})
    shaper.reset(quat.IDENTITY)
    goal = math.radians(2.0)
    trace = run_roll_step(shaper, goal, 2000)
    errors = [goal - a for a, _ in trace]
    i = 1200
    ratio = errors[i + 40] / errors[i]
    assert ratio == pytest.approx(math.exp(-40 * DT / 0.2), rel=0.02)


def test_yaw_slew_limits_the_yaw_rate():
    shaper = AttitudeInputShaper()  # ATC_SLEW_YAW 6000 cdeg/s = 60 °/s
    shaper.reset(quat.IDENTITY)
    peak = 0.0
    for _ in range(2000):
        out = shaper.input_euler_angle_roll_pitch_yaw(0.0, 0.0, math.radians(120.0), True, shaper.q_target, DT)
        peak = max(peak, abs(shaper.target_rate[2]))
    assert peak == pytest.approx(math.radians(60.0), rel=1e-9)
    assert quat.yaw(out.q_target) == pytest.approx(math.radians(120.0), abs=1e-4)


def test_without_feedforward_the_target_jumps_to_desired():
    shaper = AttitudeInputShaper({"ATC_RATE_FF_ENAB": 0})
    shaper.reset(quat.IDENTITY)
    out = shaper.input_euler_angle_roll_pitch_yaw(0.2, -0.1, 0.5, False, quat.IDENTITY, DT)
    assert quat.to_euler(out.q_target) == pytest.approx((0.2, -0.1, 0.5))
    assert out.rate_ff == (0.0, 0.0, 0.0)
    slewed = AttitudeInputShaper({"ATC_RATE_FF_ENAB": 0})
    slewed.reset(quat.IDENTITY)
    out = slewed.input_euler_angle_roll_pitch_yaw(0.0, 0.0, 1.0, True, quat.IDENTITY, 0.1)
    assert quat.yaw(out.q_target) == pytest.approx(math.radians(6.0))


def test_input_quaternion_converges_to_the_desired_attitude():
    shaper = AttitudeInputShaper()
    shaper.reset(quat.from_euler(0.1, 0.0, -0.5))
    desired = quat.from_euler(-0.4, 0.3, 1.2)
    for _ in range(1600):
        out = shaper.input_quaternion(desired, shaper.q_target, DT)
    assert quat.angle_between(out.q_target, desired) < 1e-4
    assert max(abs(x) for x in shaper.target_rate) < 1e-3


def test_acro_shapes_body_rates_and_integrates_the_target():
    shaper = AttitudeInputShaper()
    shaper.reset(quat.IDENTITY)
    rates = []
    for _ in range(400):
        shaper.input_rate_bf_roll_pitch_yaw((1.0, 0.0, 0.0), shaper.q_target, DT)
        rates.append(shaper.target_rate[0])
    accel = math.radians(1100.0)
    assert max(b - a for a, b in itertools.pairwise([0.0, *rates])) <= accel * DT * (1 + 1e-9)
    assert rates[-1] == pytest.approx(1.0)
    # 1 s at 1 rad/s, less the acceleration ramp (1/(2·accel)) and the one-step integration lag.
    roll = quat.to_euler(shaper.q_target)[0]
    assert roll == pytest.approx(1.0 - 1.0 / (2.0 * accel) - DT, abs=2e-3)


def test_feedforward_is_the_target_rate_seen_from_the_current_body():
    shaper = AttitudeInputShaper()
    target = quat.from_axis_angle((0.0, 0.0, 1.0), 0.3)
    shaper.reset(target)
    for _ in range(100):
        shaper.input_rate_bf_roll_pitch_yaw((0.4, 0.0, 0.0), target, DT)
    shaper.reset(target)
    out = shaper.input_rate_bf_roll_pitch_yaw((0.4, 0.0, 0.0), target, DT)
    assert out.rate_ff == pytest.approx(shaper.target_rate)
    # A body yawed 90° further than the target sees the target's roll rate on its −y axis.
    body = quat.mul(out.q_target, quat.from_axis_angle((0.0, 0.0, 1.0), math.pi / 2))
    out = shaper.input_rate_bf_roll_pitch_yaw((0.4, 0.0, 0.0), body, DT)
    r = shaper.target_rate[0]
    assert out.rate_ff == pytest.approx((0.0, -r, 0.0), abs=1e-12)


def test_feedforward_fades_with_the_thrust_error_angle():
    shaper = AttitudeInputShaper()
    shaper.reset(quat.IDENTITY)
    shaper.input_rate_bf_roll_pitch_yaw((0.0, 0.0, 0.3), quat.IDENTITY, DT)
    for tilt_deg, scale in ((20.0, 1.0), (45.0, 0.5), (70.0, 0.0)):
        body = quat.from_axis_angle((1.0, 0.0, 0.0), math.radians(tilt_deg))
        out = shaper.input_rate_bf_roll_pitch_yaw((0.0, 0.0, 0.3), body, DT)
        assert out.thrust_error_angle == pytest.approx(math.radians(tilt_deg), abs=1e-3)
        assert out.feedforward_scale == pytest.approx(scale, abs=0.01)


def test_combine_blends_the_yaw_demand_toward_the_gyro():
    shaped = ShapedAttitude(quat.IDENTITY, (0.5, -0.5, 0.2), 0.5, math.radians(45.0))
    combined = combine_with_feedforward((1.0, 1.0, 0.4), shaped, (0.0, 0.0, -1.0))
    assert combined == pytest.approx((1.5, 0.5, 0.5 * -1.0 + 0.5 * (0.4 + 0.2)))
    full = ShapedAttitude(quat.IDENTITY, (0.5, -0.5, 0.2), 1.0, 0.0)
    assert combine_with_feedforward((1.0, 1.0, 0.4), full, (9.0, 9.0, 9.0)) == pytest.approx((1.5, 0.5, 0.6))
    none = ShapedAttitude(quat.IDENTITY, (0.0, 0.0, 0.2), 0.0, math.radians(80.0))
    assert combine_with_feedforward((1.0, 1.0, 0.4), none, (0.0, 0.0, -1.0)) == pytest.approx((1.0, 1.0, -1.0))


def test_heading_reset_moves_the_target_with_the_estimate():
    shaper = AttitudeInputShaper()
    q = quat.from_euler(0.1, 0.2, 0.3)
    shaper.reset(q)
    delta = quat.from_axis_angle((0.0, 0.0, 1.0), 0.5)
    shaper.adapt_to_reset(delta)
    assert shaper.q_target == pytest.approx(quat.mul(delta, q), abs=1e-12)


def test_without_shaping_the_setpoint_goes_to_the_controller_as_px4_gives_it():
    q, q_d = quat.from_euler(0.1, 0.0, 0.0), quat.from_euler(0.3, -0.1, 0.5)
    shaping = AttitudeSetpointShaping(enabled=False)
    rates = shaping.rates(AttitudeControl(), q_d, 0.2, q, (9.0, 9.0, 9.0), DT)
    plain = AttitudeControl()
    plain.set_attitude_setpoint(q_d, 0.2)
    assert rates == plain.update(q)
    assert not shaping.engaged


def test_shaping_engages_from_the_measured_attitude_at_rest_until_released():
    q_d = quat.from_euler(0.5, 0.0, 0.0)
    shaping = AttitudeSetpointShaping(enabled=True)
    control = AttitudeControl()
    start = quat.from_euler(0.0, 0.2, 0.0)
    shaping.rates(control, q_d, math.nan, start, (0.0, 0.0, 0.0), DT)
    assert shaping.engaged
    # One step from the measured attitude at rest: the target has barely moved toward q_d.
    assert quat.angle_between(shaping.shaper.q_target, start) < 0.01
    for _ in range(40):
        shaping.rates(control, q_d, math.nan, start, (0.0, 0.0, 0.0), DT)
    assert quat.angle_between(shaping.shaper.q_target, start) > 0.05
    # Engaged, the target goes on from where it was; released, it starts again from the measured attitude.
    elsewhere = quat.from_euler(0.0, -0.3, 1.0)
    shaping.rates(control, q_d, math.nan, elsewhere, (0.0, 0.0, 0.0), DT)
    assert quat.angle_between(shaping.shaper.q_target, elsewhere) > 0.3
    shaping.release()
    assert not shaping.engaged
    shaping.rates(control, q_d, math.nan, elsewhere, (0.0, 0.0, 0.0), DT)
    assert quat.angle_between(shaping.shaper.q_target, elsewhere) < 0.01


def test_a_parameter_change_releases_the_shaper_and_can_turn_it_off():
    shaping = AttitudeSetpointShaping(enabled=True)
    shaping.rates(AttitudeControl(), quat.IDENTITY, math.nan, quat.IDENTITY, (0.0, 0.0, 0.0), DT)
    shaping.set_params({"ATC_INPUT_TC": 0.2}, enabled=True)
    assert not shaping.engaged
    shaping.set_params({}, enabled=False)
    shaping.rates(AttitudeControl(), quat.IDENTITY, math.nan, quat.IDENTITY, (0.0, 0.0, 0.0), DT)
    assert not shaping.engaged and not shaping.enabled


# Inputs within FLT_EPSILON of a limit, where ArduPilot's AP_Math (is_zero, is_positive) decides the branch.
def test_an_acceleration_limit_below_flt_epsilon_is_no_limit_as_upstream():
    assert sqrt_controller(1.0, 2.0, 1e-9, 0.0) == 2.0  # the linear branch, not sqrt(2·1e-9·…)
    assert sqrt_controller(-1.0, 2.0, -1e-9, 0.0) == -2.0
    assert sqrt_controller(1e-9, 0.0, 1.0, 0.0) == 0.0  # an error below FLT_EPSILON with p = 0: none
    assert inv_sqrt_controller(2.0, 1e-9, 1.0) == pytest.approx(2.0)  # p below FLT_EPSILON: the sqrt branch


def test_within_flt_epsilon_of_a_vertical_pitch_no_euler_rates_are_made_up():
    almost_vertical = (0.0, math.pi / 2 - 1e-10, 0.0)
    assert ang_vel_to_euler_rate(almost_vertical, (0.1, 0.2, 0.3)) is None
    shaper = AttitudeInputShaper()
    q = quat.from_euler(*almost_vertical)
    shaper.reset(q)
    for _ in range(5):
        out = shaper.input_euler_angle_roll_pitch_yaw(0.0, almost_vertical[1], 0.2, False, q, DT)
    assert all(abs(r) < 100.0 for r in shaper.target_rate) and quat.is_finite(out.q_target)
