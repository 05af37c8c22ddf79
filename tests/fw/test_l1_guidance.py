import math

import pytest

from stack.fw.l1_guidance import L1Guidance, crosstrack_error
from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.mathlib.vector import line_crossing_point

A = (0.0, 0.0)
B = (100.0, 0.0)


def test_l1_distance_and_gain_from_period_and_damping():
    l1 = L1Guidance(period=20.0, damping=0.75)
    l1.navigate_waypoints(A, B, (10.0, 0.0), (10.0, 0.0))
    assert l1.l1_distance == pytest.approx(0.75 * 20.0 / math.pi * 10.0)
    assert l1.switch_distance(5.0) == 5.0
    assert l1.switch_distance(100.0) == pytest.approx(l1.l1_distance)


def test_on_the_line_no_crosstrack_and_no_lateral_acceleration():
    l1 = L1Guidance()
    a = l1.navigate_waypoints(A, B, (30.0, 0.0), (12.0, 0.0))
    assert l1.crosstrack_error == 0.0
    assert a == 0.0
    assert l1.roll_setpoint == 0.0
    assert l1.l1_point == pytest.approx((30.0 + l1.l1_distance, 0.0))


def test_crosstrack_sign_and_lateral_acceleration_steers_back():
    l1 = L1Guidance()
    # East of a northbound track = right of it: positive cross-track, turn left (negative).
    a_right = l1.navigate_waypoints(A, B, (30.0, 5.0), (12.0, 0.0))
    assert l1.crosstrack_error == pytest.approx(5.0)
    assert crosstrack_error(A, B, (30.0, 5.0)) == pytest.approx(5.0)
    assert a_right < 0.0
    assert l1.roll_setpoint < 0.0
    a_left = l1.navigate_waypoints(A, B, (30.0, -5.0), (12.0, 0.0))
    assert l1.crosstrack_error == pytest.approx(-5.0)
    assert a_left == pytest.approx(-a_right)
    # The L1 point lies on the track, ahead of the vehicle, at L1 from it.
    assert l1.l1_point[1] == pytest.approx(0.0, abs=1e-9)
    assert math.dist(l1.l1_point, (30.0, -5.0)) == pytest.approx(l1.l1_distance)


def test_line_tracking_hand_worked():
    l1 = L1Guidance(period=20.0, damping=0.75)
    v = 10.0
    position, velocity = (30.0, 5.0), (v * math.cos(0.1), v * math.sin(0.1))
    a = l1.navigate_waypoints(A, B, position, velocity)
    l1_distance = 0.75 * 20.0 / math.pi * v
    # Heading 0.1 rad right of the track adds to the 5 m right offset: both steer left.
    eta = math.asin(-5.0 / l1_distance) - 0.1
    assert a == pytest.approx(4.0 * 0.75**2 * v * v / l1_distance * math.sin(eta))
    assert l1.bearing_error == pytest.approx(eta)


def test_eta1_is_limited_to_45_degrees():
    l1 = L1Guidance()
    l1.navigate_waypoints(A, B, (30.0, 200.0), (10.0, 0.0))
    assert l1.nav_bearing == pytest.approx(-math.pi / 4.0, abs=1e-4)


def test_far_behind_a_flies_to_a():
    l1 = L1Guidance()
    position = (-200.0, 50.0)
    l1.navigate_waypoints(A, B, position, (0.0, 10.0))
    assert l1.nav_bearing == pytest.approx(math.atan2(-50.0, 200.0))
    # Flying east, A is to the north-west-ish (left): turn left.
    assert l1.lateral_acceleration < 0.0


def test_past_b_flies_back_to_b():
    l1 = L1Guidance()
    position = (130.0, 10.0)
    l1.navigate_waypoints(A, B, position, (10.0, 0.0))
    assert l1.nav_bearing == pytest.approx(math.atan2(-10.0, -30.0))
    assert abs(l1.bearing_error) == pytest.approx(math.pi / 2.0)


def test_between_waypoints_uses_the_line_logic():
    l1 = L1Guidance()
    # Slightly behind A but close: still the line logic (not "fly to A").
    l1.navigate_waypoints(A, B, (-5.0, 3.0), (10.0, 0.0))
    eta1 = math.asin(-3.0 / l1.l1_distance)
    assert l1.nav_bearing == pytest.approx(eta1)


def test_converges_onto_the_track():
    l1 = L1Guidance(period=10.0)
    x, y, course, speed = 0.0, 30.0, 0.0, 8.0
    dt = 0.05
    for _ in range(round(60.0 / dt)):
        a = l1.navigate_waypoints(A, (1000.0, 0.0), (x, y), (speed * math.cos(course), speed * math.sin(course)), dt)
        course += a / speed * dt
        x += speed * math.cos(course) * dt
        y += speed * math.sin(course) * dt
    assert abs(y) < 0.05
    assert abs(course) < 0.01


def test_roll_setpoint_limit_and_slew():
    l1 = L1Guidance(roll_limit=math.radians(30.0), roll_slew_rate=math.radians(90.0))
    l1.navigate_heading(math.pi / 2.0, 0.0, (20.0, 0.0))
    assert l1.roll_setpoint == pytest.approx(math.radians(30.0))
    # Reversing the turn is rate-limited: 90 °/s over 0.1 s.
    l1.navigate_heading(-math.pi / 2.0, 0.0, (20.0, 0.0), dt=0.1)
    assert l1.roll_setpoint == pytest.approx(math.radians(30.0 - 9.0))


def test_navigate_heading():
    l1 = L1Guidance(period=20.0)
    a = l1.navigate_heading(0.3, 0.1, (10.0, 0.0))
    omega = math.sqrt(2.0) * math.pi / 20.0
    assert a == pytest.approx(2.0 * math.sin(0.2) * 10.0 * omega)
    assert l1.roll_setpoint == pytest.approx(math.atan(a / G))
    assert l1.crosstrack_error == 0.0
    assert l1.navigate_level_flight(0.1) == 0.0


def test_lateral_acceleration_vector_is_right_of_the_velocity():
    l1 = L1Guidance()
    l1.navigate_heading(math.pi / 2.0, 0.0, (10.0, 0.0))
    an, ae = l1.lateral_acceleration_ne
    assert an == pytest.approx(0.0)
    assert ae == pytest.approx(l1.lateral_acceleration)
    assert ae > 0.0


@pytest.mark.parametrize("direction", [1, -1])
def test_loiter_converges_to_the_circle(direction):
    l1 = L1Guidance(period=15.0)
    center, radius, speed = (50.0, -20.0), 60.0, 12.0
    x, y, course = -150.0, 80.0, 0.5
    dt = 0.05
    distances = []
    directions = []
    for _ in range(round(180.0 / dt)):
        vel = (speed * math.cos(course), speed * math.sin(course))
        a = l1.navigate_loiter(center, (x, y), radius, direction, vel, dt)
        course += a / speed * dt
        x += speed * math.cos(course) * dt
        y += speed * math.sin(course) * dt
        rel = (x - center[0], y - center[1])
        distances.append(math.hypot(*rel))
        directions.append(rel[0] * vel[1] - rel[1] * vel[0])
    last_minute = distances[-round(60.0 / dt):]
    assert max(abs(d - radius) for d in last_minute) < 0.05 * radius
    assert l1.circle_mode
    # Clockwise in NED (north→east) for +1: the radius vector turns toward east.
    assert all(d * direction > 0.0 for d in directions[-round(60.0 / dt):])


def test_line_crossing_point():
    a, b = (0.0, 0.0, 0.0), (10.0, 0.0, 0.0)
    assert line_crossing_point(a, b, (3.0, 4.0, 0.0), 5.0) == pytest.approx((6.0, 0.0, 0.0))
    assert line_crossing_point(a, b, (3.0, 4.0, 0.0), 3.0) == pytest.approx((3.0, 0.0, 0.0))
    assert line_crossing_point(a, a, (3.0, 4.0, 0.0), 5.0) == a


# Inputs where the direction from a point to itself is asked for: ECL L1 (PX4 v1.13) answers these.
def test_exactly_on_b_the_line_is_tracked_as_upstream_does():
    l1 = L1Guidance(period=20.0, damping=0.75)
    accel = l1.navigate_waypoints(A, B, B, (0.0, 10.0))  # on B, flying east, across the northbound leg
    # Upstream: B→vehicle normalizes to NaN, so "past B" is false and the line logic turns left onto the leg.
    assert accel == pytest.approx(-4.71, abs=0.01)
    assert l1.target_bearing == 0.0


def test_at_the_loiter_centre_the_bearing_to_it_is_zero():
    l1 = L1Guidance()
    l1.navigate_loiter((5.0, 5.0), (5.0, 5.0), 60.0, 1, (0.0, 10.0))
    assert l1.target_bearing == 0.0
    l1.navigate_loiter((5.0, 5.0), (5.0, -95.0), 60.0, 1, (0.0, 10.0))
    assert l1.target_bearing == pytest.approx(math.pi / 2)  # the centre lies east
