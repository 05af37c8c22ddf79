import math
import random

import pytest

from stack.mathlib.vector import line_crossing_point
from stack.posctl.position_smoothing import (
    PositionSmoothing,
    PositionSmoothingParams,
    max_speed_from_distance,
    max_speed_in_turn,
)

DT = 0.02


def test_max_speed_from_distance_hand_worked():
    # b = 4·9/4 = 9, c = −2·3·10 = −60 → v = ½(−9 + √(81 + 240)).
    assert max_speed_from_distance(4.0, 3.0, 10.0, 0.0) == pytest.approx(0.5 * (-9.0 + math.sqrt(321.0)))
    # The speed satisfies v² = v_end² + 2a(d − 2va/j).
    v = max_speed_from_distance(4.0, 3.0, 10.0, 1.0)
    assert v * v == pytest.approx(1.0 + 2.0 * 3.0 * (10.0 - 2.0 * v * 3.0 / 4.0))
    assert max_speed_from_distance(4.0, 3.0, 0.0, 2.0) == 2.0


def test_max_speed_in_turn_hand_worked():
    assert max_speed_in_turn(math.pi / 2.0, 1.5, 2.0) == pytest.approx(math.sqrt(3.0))
    assert max_speed_in_turn(0.0, 1.5, 2.0) == 0.0


def _fly(ps, waypoints, *, duration, position_of=None):
    """Fly the mission on the trajectory itself (or on position_of(point)), switching waypoints on
    ``reached``. Returns the trajectory samples and the times waypoints were reached."""
    index = 1
    samples = []
    reached_at = []
    t = 0.0
    while t < duration:
        last = index == len(waypoints) - 1
        triplet = (waypoints[index - 1], waypoints[index], waypoints[min(index + 1, len(waypoints) - 1)])
        vehicle = ps.point().position if position_of is None else position_of(t)
        point = ps.generate(DT, vehicle, triplet, stop_at_target=last)
        t += DT
        samples.append(point)
        if not last and ps.reached(waypoints[index]):
            reached_at.append(t)
            index += 1
    return samples, reached_at


SQUARE = [(0.0, 0.0, -10.0), (20.0, 0.0, -10.0), (20.0, 20.0, -10.0), (0.0, 20.0, -6.0), (0.0, 0.0, -10.0)]


def test_reaches_all_waypoints_and_stops_at_the_last():
    ps = PositionSmoothing(PositionSmoothingParams(nav_acc_rad=2.0))
    ps.reset(SQUARE[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    samples, reached_at = _fly(ps, SQUARE, duration=60.0)
    assert len(reached_at) == len(SQUARE) - 2
    final = samples[-1]
    assert final.position == pytest.approx(SQUARE[-1], abs=0.02)
    assert math.sqrt(sum(v * v for v in final.velocity)) < 0.01
    # It settles without overshooting the last waypoint noticeably.
    approach = [s.position[1] for s in samples if s.position[0] < 1.0]
    assert min(approach) > -0.05


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_random_missions_respect_the_limits(seed):
    rng = random.Random(seed)
    params = PositionSmoothingParams(
        mpc_xy_cruise=rng.uniform(3.0, 10.0), nav_acc_rad=rng.uniform(0.5, 5.0), mpc_jerk_auto=rng.uniform(2.0, 8.0)
    )
    waypoints = [(0.0, 0.0, -5.0)] + [
        (rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-25, -2)) for _ in range(5)
    ]
    ps = PositionSmoothing(params)
    ps.reset(waypoints[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    samples, reached_at = _fly(ps, waypoints, duration=150.0)
    assert len(reached_at) == len(waypoints) - 2
    jerk = params.mpc_jerk_auto
    for s in samples:
        assert max(abs(c) for c in s.jerk) <= jerk + 1e-9
        assert abs(s.acceleration[0]) <= params.mpc_acc_hor + 1e-6
        assert abs(s.acceleration[1]) <= params.mpc_acc_hor + 1e-6
        assert abs(s.acceleration[2]) <= max(params.mpc_acc_up_max, params.mpc_acc_down_max) + 1e-6
        assert math.hypot(s.velocity[0], s.velocity[1]) <= params.mpc_xy_cruise * 1.02
        assert -params.mpc_z_v_auto_up - 1e-6 <= s.velocity[2] <= params.mpc_z_v_auto_up + 1e-6
    assert samples[-1].position == pytest.approx(waypoints[-1], abs=0.05)


def test_descent_respects_descent_limits():
    ps = PositionSmoothing()
    ps.reset((0.0, 0.0, -30.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    samples, _ = _fly(ps, [(0.0, 0.0, -30.0), (0.0, 0.0, -2.0)], duration=30.0)
    assert max(s.velocity[2] for s in samples) == pytest.approx(1.5, abs=1e-6)
    assert max(abs(s.acceleration[2]) for s in samples) <= 3.0 + 1e-9
    assert samples[-1].position[2] == pytest.approx(-2.0, abs=0.02)


def test_single_3d_leg_stays_on_the_line():
    start, end = (0.0, 0.0, -5.0), (20.0, 8.0, -12.0)
    ps = PositionSmoothing()
    ps.reset(start, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    samples, _ = _fly(ps, [start, end], duration=25.0)
    u = [e - s for s, e in zip(start, end, strict=True)]
    n = math.sqrt(sum(c * c for c in u))
    worst = 0.0
    for s in samples:
        d = [p - s0 for p, s0 in zip(s.position, start, strict=True)]
        along = sum(a * b for a, b in zip(d, u, strict=True)) / n
        worst = max(worst, math.sqrt(max(sum(c * c for c in d) - along * along, 0.0)))
    assert worst < 1e-6
    assert samples[-1].position == pytest.approx(end, abs=0.02)


def test_time_stretch_slows_the_trajectory_when_the_vehicle_lags():
    def run(lag):
        ps = PositionSmoothing()
        ps.reset((0.0, 0.0, -5.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        point = ps.point()
        for _ in range(100):
            vehicle = (point.position[0] - lag, point.position[1], point.position[2])
            point = ps.generate(DT, vehicle, ((0.0, 0.0, -5.0), (50.0, 0.0, -5.0), (50.0, 0.0, -5.0)))
        return point.position[0]

    free = run(0.0)
    half = run(1.0)  # lag = MPC_XY_ERR_MAX / 2
    frozen = run(2.5)
    assert free > 0.5
    assert half < 0.75 * free
    assert frozen == 0.0


def test_vehicle_ahead_of_the_trajectory_does_not_slow_it():
    def run(offset):
        ps = PositionSmoothing()
        ps.reset((0.0, 0.0, -5.0), (2.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        point = ps.point()
        for _ in range(100):
            vehicle = (point.position[0] + offset, point.position[1], point.position[2])
            point = ps.generate(DT, vehicle, ((0.0, 0.0, -5.0), (50.0, 0.0, -5.0), (50.0, 0.0, -5.0)))
        return point.position[0]

    assert run(1.5) == pytest.approx(run(0.0))


def test_turning_aims_at_the_l1_crossing_point():
    ps = PositionSmoothing(PositionSmoothingParams(nav_acc_rad=2.0))
    # Moving north at 5 m/s while the new leg goes east from (20, 0) to (20, 40): turning.
    ps.reset((18.0, -3.0, -10.0), (5.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    previous, target = (20.0, 0.0, -10.0), (20.0, 40.0, -10.0)
    ps.generate(DT, (18.0, -3.0, -10.0), (previous, target, target))
    aim = line_crossing_point(previous, target, (18.0, -3.0, -10.0), 5.0)
    assert aim == pytest.approx((20.0, -3.0 + math.sqrt(21.0), -10.0))
    vx, vy, vz = ps.unsmoothed_velocity
    assert math.atan2(vy, vx) == pytest.approx(math.atan2(aim[1] + 3.0, aim[0] - 18.0))
    assert vz == pytest.approx(0.0)
    # Not turning (velocity aligned with the target direction): aims at the target itself.
    ps.reset((20.0, 0.0, -10.0), (0.0, 5.0, 0.0), (0.0, 0.0, 0.0))
    ps.generate(DT, (20.0, 0.0, -10.0), (previous, target, target))
    assert ps.unsmoothed_velocity[0] == pytest.approx(0.0)


def test_reached_uses_both_acceptance_radii():
    ps = PositionSmoothing(PositionSmoothingParams(nav_acc_rad=2.0, nav_mc_alt_rad=0.8))
    target = (10.0, 0.0, -5.0)
    assert ps.reached(target, (8.5, 1.0, -5.5))
    assert not ps.reached(target, (8.0, 1.0, -5.0))
    assert not ps.reached(target, (10.0, 0.0, -6.0))
    ps.reset(target, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert ps.reached(target)


def test_a_target_not_yet_reached_holds_the_trajectory_at_it():
    # The navigator moves on only once the vehicle is within the acceptance radius. Until then the trajectory must
    # stay at the target, even once it has gone past it: aiming along the leg beyond it would fly on forever.
    ps = PositionSmoothing(PositionSmoothingParams(nav_acc_rad=0.1))
    previous, target, following = (20.0, 20.0, -10.0), (0.0, 20.0, -10.0), (0.0, 0.0, -10.0)
    ps.reset(previous, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    lagging = (0.0, 0.3, 0.0)  # the vehicle, beside the trajectory, never within 0.1 m of the target
    beyond = 0.0
    for _ in range(round(60.0 / DT)):
        p = ps.point().position
        point = ps.generate(DT, (p[0] + lagging[0], p[1] + lagging[1], p[2]), (previous, target, following))
        beyond = max(beyond, -point.position[0])
    assert beyond < 0.2
    assert math.dist(ps.point().position, target) < 0.01
    assert math.hypot(*ps.point().velocity[:2]) < 0.01


def test_its_parameters_default_to_the_catalogues():
    """One definition: a default restated here once drifted (NAV_ACC_RAD 10 m against the catalogue's 2 m)."""
    from dataclasses import fields

    from stack.params import catalogue

    defaults = PositionSmoothingParams()
    for f in fields(PositionSmoothingParams):
        assert getattr(defaults, f.name) == catalogue.get(f.name.upper()).default, f.name
