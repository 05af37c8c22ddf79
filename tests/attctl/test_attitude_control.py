"""AttitudeControl (PX4 quaternion law) and the older PX4 rotation-matrix attitude error."""

import math
import random

import pytest

from stack.attctl.attitude_control import AttitudeControl, attitude_error_dcm
from stack.mathlib import quaternion as quat
from stack.mathlib import vector as vec

# PX4 AttitudeControlTest inputs, including the antipodal 180° flips about x, y and z.
TEST_QUATS = [
    (1.0, 0.0, 0.0, 0.0),
    (0.0, 1.0, 0.0, 0.0),
    (0.0, 0.0, 1.0, 0.0),
    (0.0, 0.0, 0.0, 1.0),
    (0.698, 0.024, -0.681, -0.220),
    (-0.820, -0.313, 0.225, -0.423),
    (0.599, -0.172, 0.755, -0.204),
    (0.216, -0.662, 0.290, -0.656),
]


def unit_gain_controller(yaw_weight: float = 1.0) -> AttitudeControl:
    c = AttitudeControl()
    c.set_gains((1.0, 1.0, 1.0), yaw_weight)
    c.set_rate_limits((100.0, 100.0, 100.0))
    return c


def test_zero_error_gives_zero_rates():
    c = AttitudeControl()
    assert c.update(quat.IDENTITY) == (0.0, 0.0, 0.0)


def test_pure_yaw_step_gives_pure_yaw_rate_of_gain_times_error():
    c = AttitudeControl()  # MC_YAW_P 2.8, MC_YAW_WEIGHT 0.4
    c.set_attitude_setpoint(quat.from_axis_angle((0.0, 0.0, 1.0), 0.1))
    rate = c.update(quat.IDENTITY)
    assert rate[0] == 0.0 and rate[1] == 0.0
    assert rate[2] == pytest.approx(0.28, abs=1e-4)
    # Exactly the weighted law: (P / w) · 2 sin(w · ψ / 2).
    assert rate[2] == pytest.approx(2.8 / 0.4 * 2.0 * math.sin(0.4 * 0.05), rel=1e-12)


def test_zero_yaw_weight_drops_yaw_without_nan():
    c = AttitudeControl({"MC_YAW_WEIGHT": 0.0})
    c.set_attitude_setpoint(quat.from_axis_angle((0.0, 0.0, 1.0), 0.1))
    assert c.update(quat.IDENTITY) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("start", range(len(TEST_QUATS)))
@pytest.mark.parametrize("goal", range(len(TEST_QUATS)))
def test_error_shrinks_monotonically_and_converges_including_antipodal_flips(start, goal):
    c = AttitudeControl()
    c.set_gains((0.5, 0.6, 0.3), 0.4)
    c.set_rate_limits((100.0, 100.0, 100.0))
    state = quat.normalized(TEST_QUATS[start])
    target = quat.normalized(TEST_QUATS[goal])
    c.set_attitude_setpoint(target)
    previous = math.inf
    for _ in range(100):
        rate = c.update(state)
        magnitude = vec.norm(rate)
        if magnitude < 1e-12:
            break
        assert magnitude < previous
        previous = magnitude
        # Apply the rate for one unit of time, then flip to the antipodal quaternion (unwinding check).
        state = quat.mul(state, quat.from_rotation_vector(rate))
        state = (-state[0], -state[1], -state[2], -state[3])
    assert quat.angle_between(state, target) < 1e-6


def test_rate_limits_are_respected_per_axis():
    c = AttitudeControl()  # 220, 220, 200 deg/s
    limits = (math.radians(220.0), math.radians(220.0), math.radians(200.0))
    rng = random.Random(4)
    hit = [False, False, False]
    for _ in range(300):
        q = quat.normalized(tuple(rng.gauss(0.0, 1.0) for _ in range(4)))
        c.set_attitude_setpoint(quat.normalized(tuple(rng.gauss(0.0, 1.0) for _ in range(4))), rng.uniform(-5, 5))
        rate = c.update(q)
        for i in range(3):
            assert abs(rate[i]) <= limits[i] + 1e-12
            hit[i] |= abs(rate[i]) == limits[i]
    assert all(hit)


def test_large_roll_error_saturates_at_roll_rate_max():
    c = AttitudeControl()
    c.set_attitude_setpoint(quat.from_axis_angle((1.0, 0.0, 0.0), math.radians(90.0)))
    # Unlimited it would be 4 · 2 sin(45°) = 5.66 rad/s; MC_ROLLRATE_MAX is 220 °/s.
    assert c.update(quat.IDENTITY) == (math.radians(220.0), 0.0, 0.0)


def test_yaw_feedforward_is_world_z_rate_seen_from_the_body():
    c = AttitudeControl()
    tilted = quat.from_axis_angle((0.0, 1.0, 0.0), 0.5)
    c.set_attitude_setpoint(tilted, 0.5)
    rate = c.update(tilted)
    assert rate == pytest.approx((-math.sin(0.5) * 0.5, 0.0, math.cos(0.5) * 0.5), abs=1e-12)
    c.set_attitude_setpoint(tilted, math.nan)
    assert c.update(tilted) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)


def test_heading_reset_shifts_the_setpoint_with_the_estimate():
    c = AttitudeControl()
    q = quat.from_euler(0.1, -0.2, 0.3)
    c.set_attitude_setpoint(quat.from_euler(0.3, 0.1, 1.0))
    before = c.update(q)
    delta = quat.from_axis_angle((0.0, 0.0, 1.0), 0.7)
    c.adapt_to_reset(delta)
    after = c.update(quat.mul(delta, q))
    assert after == pytest.approx(before, abs=1e-12)


def test_dcm_form_agrees_with_quaternion_form_on_pure_tilt_errors():
    # The old law uses the tilt angle α where the quaternion law uses 2·sin(α/2), along the same axis.
    rng = random.Random(0)
    c = unit_gain_controller()
    for _ in range(50):
        heading = quat.from_axis_angle((0.0, 0.0, 1.0), rng.uniform(-math.pi, math.pi))
        q = quat.mul(heading, quat.from_axis_angle(vec.normalized((rng.uniform(-1, 1), rng.uniform(-1, 1), 0.0)),
                                                   rng.uniform(0.0, 0.6)))
        # A pure thrust-axis error: the shortest rotation taking the body z axis onto another direction.
        target_axis = vec.normalized((rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 1.0)))
        q_sp = quat.mul(quat.from_two_vectors(quat.dcm_z(q), target_axis), q)
        e_z = quat.dcm_z(q)
        alpha = math.atan2(vec.norm(vec.cross(e_z, target_axis)), vec.dot(e_z, target_axis))
        c.set_attitude_setpoint(q_sp)
        e_quat = c.update(q)
        e_dcm = attitude_error_dcm(q, q_sp)
        assert e_dcm[2] == pytest.approx(0.0, abs=1e-9)
        assert vec.norm(e_quat) == pytest.approx(2.0 * math.sin(alpha / 2.0), rel=1e-9)
        assert vec.norm(e_dcm) == pytest.approx(alpha, rel=1e-9)
        assert vec.dot(vec.normalized(e_dcm), vec.normalized(e_quat)) == pytest.approx(1.0, abs=1e-9)


def test_dcm_form_yaw_error_is_the_angle_on_a_level_setpoint():
    q = quat.from_axis_angle((0.0, 0.0, 1.0), 0.4)
    for delta in (0.05, 0.3, -1.0):
        q_sp = quat.mul(quat.from_axis_angle((0.0, 0.0, 1.0), delta), q)
        assert attitude_error_dcm(q, q_sp) == pytest.approx((0.0, 0.0, delta), abs=1e-12)
        # The quaternion law: (P/w)·2 sin(w·Δ/2), i.e. P·Δ to first order.
        c = AttitudeControl({"MC_YAW_P": 1.0})
        c.set_attitude_setpoint(q_sp)
        assert c.update(q)[2] == pytest.approx(2.0 / 0.4 * math.sin(0.4 * delta / 2.0), rel=1e-12)


def test_dcm_form_weights_yaw_by_cos_squared_of_the_setpoint_tilt():
    # Same thrust axis, heading differing by Δ about it: the old law scales yaw by R_sp(2,2)² = cos²(tilt),
    # the quaternion law does not.
    delta = 0.01
    for tilt_angle in (0.3, 0.8, 1.2):
        q = quat.from_axis_angle((1.0, 0.0, 0.0), tilt_angle)
        q_sp = quat.mul(q, quat.from_axis_angle((0.0, 0.0, 1.0), delta))
        e_dcm = attitude_error_dcm(q, q_sp)
        assert e_dcm[0] == pytest.approx(0.0, abs=1e-12) and e_dcm[1] == pytest.approx(0.0, abs=1e-12)
        assert e_dcm[2] == pytest.approx(delta * math.cos(tilt_angle) ** 2, rel=1e-9)
        c = unit_gain_controller(yaw_weight=1.0)
        c.set_attitude_setpoint(q_sp)
        assert c.update(q)[2] == pytest.approx(2.0 * math.sin(delta / 2.0), rel=1e-9)


def test_dcm_form_blends_in_the_direct_rotation_beyond_ninety_degrees():
    q_sp = quat.from_axis_angle((1.0, 0.0, 0.0), math.radians(170.0))
    assert attitude_error_dcm(quat.IDENTITY, q_sp) == pytest.approx((math.radians(170.0), 0.0, 0.0), abs=1e-12)
    q_sp = quat.mul(q_sp, quat.from_axis_angle((0.0, 0.0, 1.0), 0.5))
    e = attitude_error_dcm(quat.IDENTITY, q_sp)
    direct = quat.to_rotation_vector(q_sp)
    assert all(math.isfinite(x) for x in e)
    # cos(170°)² · yaw_w ≈ 0.94 of the result is the direct rotation.
    assert vec.norm(vec.sub(e, direct)) < 0.1 * vec.norm(direct)


# Inputs where the answer hangs on a half turn; PX4's AttitudeControl (float32) gives these rate setpoints.
ROLL_RATE_MAX = math.radians(220.0)


@pytest.mark.parametrize("q_sp", [(0.0, -1.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)])
def test_a_half_turn_in_roll_from_level_is_the_same_whichever_sign_names_it(q_sp):
    c = AttitudeControl()
    c.set_attitude_setpoint(q_sp)  # q_sp and -q_sp: one attitude, one answer (upstream +3.84 rad/s)
    assert c.update(quat.IDENTITY) == pytest.approx((ROLL_RATE_MAX, 0.0, 0.0), abs=1e-6)


def test_a_thrust_axis_exactly_reversed_turns_about_upstreams_axis():
    c = AttitudeControl()
    q = quat.from_euler(0.0, 0.5, 0.0)
    c.set_attitude_setpoint(quat.mul(q, (0.0, 0.0, 1.0, 0.0)))
    assert c.update(q) == pytest.approx((ROLL_RATE_MAX, -ROLL_RATE_MAX, 0.0), abs=1e-6)


def test_canonical_looks_past_rounding_noise_as_px4_does():
    assert quat.canonical((1e-9, -1.0, 0.0, 0.0)) == (-1e-9, 1.0, -0.0, -0.0)
    assert quat.canonical((-1e-9, 0.0, 0.0, 1.0)) == (-1e-9, 0.0, 0.0, 1.0)
    assert quat.canonical((-0.5, 0.5, 0.5, 0.5)) == (0.5, -0.5, -0.5, -0.5)


def test_opposite_vectors_turn_about_src_cross_its_smallest_axis():
    assert quat.from_two_vectors((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)) == pytest.approx((0.0, -1.0, 0.0, 0.0))
    assert quat.from_two_vectors((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)) == pytest.approx((0.0, 0.0, -1.0, 0.0))
    half = quat.from_two_vectors((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    assert half == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)))
