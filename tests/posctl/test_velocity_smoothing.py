import math
import random

import pytest

from stack.posctl.velocity_smoothing import VelocitySmoothing, VelocitySmoothing3D

TOL = 1e-9


def _integrate(vs, duration, dt):
    for _ in range(round(duration / dt)):
        vs.update_traj(dt)


def test_triangular_profile_hand_worked():
    # 0 → 1 m/s with j = 1, a_max = 1: a peaks at exactly 1 after 1 s, no constant phase.
    vs = VelocitySmoothing(max_jerk=1.0, max_accel=1.0, max_vel=5.0)
    vs.update_durations(1.0)
    assert (vs.t1, vs.t2, vs.t3) == pytest.approx((1.0, 0.0, 1.0))
    vs.update_traj(1.0)
    assert (vs.jerk, vs.accel, vs.vel, vs.pos) == pytest.approx((1.0, 1.0, 0.5, 1.0 / 6.0))
    vs.update_traj(1.0)
    assert (vs.accel, vs.vel, vs.pos) == pytest.approx((0.0, 1.0, 1.0))
    vs.update_traj(1.0)
    assert (vs.jerk, vs.accel, vs.vel, vs.pos) == pytest.approx((0.0, 0.0, 1.0, 2.0))


def test_trapezoidal_profile_hand_worked():
    # 0 → 5 m/s with j = 4, a_max = 3: T1 = T3 = 0.75 s, T2 = (5 − 3·0.75)/3 s.
    vs = VelocitySmoothing(max_jerk=4.0, max_accel=3.0, max_vel=12.0)
    vs.update_durations(5.0)
    assert (vs.t1, vs.t2, vs.t3) == pytest.approx((0.75, 2.75 / 3.0, 0.75))
    vs.update_traj(vs.total_time)
    assert (vs.accel, vs.vel) == pytest.approx((0.0, 5.0))
    # Position: the time-symmetric profile has mean speed 2.5 m/s.
    assert vs.pos == pytest.approx(2.5 * vs.total_time)


def test_target_is_clamped_to_max_velocity():
    vs = VelocitySmoothing(max_jerk=4.0, max_accel=3.0, max_vel=2.0)
    vs.update_durations(-10.0)
    assert vs.velocity_target == -2.0
    vs.update_traj(vs.total_time + 1.0)
    assert vs.vel == pytest.approx(-2.0)


def test_time_stretch_slows_integration():
    a = VelocitySmoothing()
    b = VelocitySmoothing()
    a.update_durations(3.0)
    b.update_durations(3.0)
    a.update_traj(0.5)
    for _ in range(10):
        b.update_traj(0.1, time_stretch=0.5)
    assert (b.pos, b.vel, b.accel) == pytest.approx((a.pos, a.vel, a.accel))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_targets_never_exceed_limits(seed):
    rng = random.Random(seed)
    j_max, a_max, v_max = rng.uniform(1.0, 10.0), rng.uniform(0.5, 5.0), rng.uniform(1.0, 10.0)
    vs = VelocitySmoothing(max_jerk=j_max, max_accel=a_max, max_vel=v_max)
    dt = rng.choice([0.004, 0.01, 0.02])
    seen = [0.0, 0.0, 0.0]
    for _ in range(100):
        target = rng.uniform(-1.5 * v_max, 1.5 * v_max)
        for _ in range(rng.randint(1, 400)):
            vs.update_traj(dt, rng.choice([1.0, 1.0, 0.3]))
            seen = [max(seen[0], abs(vs.jerk)), max(seen[1], abs(vs.accel)), max(seen[2], abs(vs.vel))]
            vs.update_durations(target)
    assert seen[0] <= j_max + TOL
    assert seen[1] <= a_max + 1e-6
    assert seen[2] <= v_max + 1e-6
    # The limits are actually reached (the check is not vacuous).
    assert seen[1] > 0.9 * a_max


def test_converges_to_target_and_stays():
    vs = VelocitySmoothing(max_jerk=4.0, max_accel=3.0, max_vel=12.0)
    for _ in range(500):
        vs.update_traj(0.01)
        vs.update_durations(-4.0)
    assert (vs.vel, vs.accel) == pytest.approx((-4.0, 0.0), abs=1e-9)


def test_reset_and_forced_state():
    vs = VelocitySmoothing()
    vs.reset(1.0, 2.0, 3.0)
    assert (vs.jerk, vs.accel, vs.vel, vs.pos) == (0.0, 1.0, 2.0, 3.0)
    vs.set_current_position(-5.0)
    vs.update_durations(2.0)
    vs.update_traj(0.0)
    assert vs.pos == -5.0


def _distance_to_line(p, origin, direction):
    d = [p[i] - origin[i] for i in range(3)]
    n = math.sqrt(sum(c * c for c in direction))
    u = [c / n for c in direction]
    along = sum(d[i] * u[i] for i in range(3))
    return math.sqrt(max(sum(c * c for c in d) - along * along, 0.0))


@pytest.mark.parametrize("direction", [(3.0, 1.0, -0.5), (0.2, -1.0, 0.9), (1.0, 0.0, 0.0)])
def test_synchronised_axes_keep_straight_lines(direction):
    vs = VelocitySmoothing3D(max_jerk=(4.0, 4.0, 4.0), max_accel=(3.0, 3.0, 4.0), max_vel=(12.0, 12.0, 3.0))
    origin = (1.0, -2.0, -10.0)
    vs.reset((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), origin)
    n = math.sqrt(sum(c * c for c in direction))
    worst = 0.0
    # Speed up, change speed along the same line, reverse, stop.
    for speed, duration in ((4.0, 3.0), (1.0, 2.0), (-2.5, 4.0), (0.0, 3.0)):
        target = tuple(speed * c / n for c in direction)
        for _ in range(round(duration / 0.01)):
            vs.update_traj(0.01)
            worst = max(worst, _distance_to_line(vs.position, origin, direction))
            vs.update_durations(target)
    assert worst < 1e-6
    assert math.sqrt(sum(c * c for c in vs.velocity)) < 1e-6


def test_unsynchronised_axes_would_leave_the_line():
    # Control experiment for the test above: the same move planned per axis is not straight.
    axes = [VelocitySmoothing(max_jerk=4.0, max_accel=3.0, max_vel=12.0) for _ in range(3)]
    direction = (3.0, 1.0, -0.5)
    n = math.sqrt(sum(c * c for c in direction))
    worst = 0.0
    for _ in range(300):
        for axis, c in zip(axes, direction, strict=True):
            axis.update_traj(0.01)
            axis.update_durations(4.0 * c / n)
        worst = max(worst, _distance_to_line([a.pos for a in axes], (0.0, 0.0, 0.0), direction))
    assert worst > 0.05


def test_3d_limits_hold_for_random_targets():
    rng = random.Random(7)
    vs = VelocitySmoothing3D(max_jerk=(4.0, 4.0, 4.0), max_accel=(3.0, 3.0, 4.0), max_vel=(5.0, 5.0, 3.0))
    seen_j = seen_a = 0.0
    seen_v = [0.0, 0.0, 0.0]
    for _ in range(60):
        target = (rng.uniform(-7, 7), rng.uniform(-7, 7), rng.uniform(-4, 4))
        for _ in range(rng.randint(1, 300)):
            vs.update_traj(0.02)
            p = vs.point()
            seen_j = max(seen_j, *map(abs, p.jerk))
            seen_a = max(seen_a, *map(abs, p.acceleration[:2]), abs(p.acceleration[2]) * 3.0 / 4.0)
            seen_v = [max(seen_v[i], abs(p.velocity[i])) for i in range(3)]
            vs.update_durations(target)
    assert seen_j <= 4.0 + TOL
    assert seen_a <= 3.0 + 1e-6
    assert seen_v[0] <= 5.0 + 1e-6 and seen_v[1] <= 5.0 + 1e-6 and seen_v[2] <= 3.0 + 1e-6
