import math

import pytest

from stack.mathlib import quaternion
from stack.posctl.control_math import (
    add_if_not_nan,
    body_z_to_attitude,
    constrain_xy,
    limit_tilt,
    thrust_to_attitude,
)


def _angle(a, b):
    d = sum(x * y for x, y in zip(a, b, strict=True))
    na = math.sqrt(sum(x * x for x in a))
    nb = math.sqrt(sum(x * x for x in b))
    return math.acos(max(-1.0, min(1.0, d / (na * nb))))


def test_add_if_not_nan():
    assert add_if_not_nan(1.0, 2.0) == 3.0
    assert add_if_not_nan(1.0, math.nan) == 1.0
    assert add_if_not_nan(math.nan, 2.0) == 2.0
    assert math.isnan(add_if_not_nan(math.nan, math.nan))


def test_constrain_xy_sum_within_limit_is_unchanged():
    assert constrain_xy((1.0, 0.0), (0.0, 1.0), 2.0) == (1.0, 1.0)


def test_constrain_xy_priority_part_too_long_is_scaled_alone():
    v = constrain_xy((3.0, 4.0), (0.0, 10.0), 2.5)
    assert v == pytest.approx((1.5, 2.0))


def test_constrain_xy_scales_feed_forward_to_reach_the_limit():
    v0 = (1.0, 0.0)
    v1 = (0.0, 5.0)
    v = constrain_xy(v0, v1, 2.0)
    assert math.hypot(*v) == pytest.approx(2.0)
    # The P part is kept entirely; only the feed-forward is shortened.
    assert v[0] == pytest.approx(1.0)
    assert v[1] == pytest.approx(math.sqrt(3.0))


def test_constrain_xy_oblique_feed_forward():
    v0 = (1.0, 1.0)
    v1 = (3.0, -1.0)
    v = constrain_xy(v0, v1, 2.5)
    assert math.hypot(*v) == pytest.approx(2.5)
    d = (v[0] - v0[0], v[1] - v0[1])
    # The remaining feed-forward is parallel to v1 and points the same way.
    assert d[0] * v1[1] - d[1] * v1[0] == pytest.approx(0.0, abs=1e-12)
    assert d[0] * v1[0] + d[1] * v1[1] > 0.0


def test_constrain_xy_zero_priority_part_uses_feed_forward_direction():
    assert constrain_xy((0.0, 0.0), (0.0, -8.0), 3.0) == pytest.approx((0.0, -3.0))


def test_constrain_xy_nan_feed_forward_propagates():
    v = constrain_xy((0.0, 0.0), (math.nan, math.nan), 3.0)
    assert math.isnan(v[0]) and math.isnan(v[1])


def test_limit_tilt_reduces_angle_and_keeps_azimuth():
    tilt = math.radians(60.0)
    azimuth = math.radians(30.0)
    body = (math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), math.cos(tilt))
    limited = limit_tilt(body, (0.0, 0.0, 1.0), math.radians(45.0))
    assert _angle(limited, (0.0, 0.0, 1.0)) == pytest.approx(math.radians(45.0))
    assert math.atan2(limited[1], limited[0]) == pytest.approx(azimuth)
    assert math.sqrt(sum(c * c for c in limited)) == pytest.approx(1.0)


def test_limit_tilt_below_limit_is_unchanged():
    body = (math.sin(0.2), 0.0, math.cos(0.2))
    assert limit_tilt(body, (0.0, 0.0, 1.0), 0.5) == pytest.approx(body)


def test_limit_tilt_upside_down_is_rotated_to_the_limit():
    limited = limit_tilt((0.0, 0.0, -1.0), (0.0, 0.0, 1.0), math.radians(30.0))
    assert _angle(limited, (0.0, 0.0, 1.0)) == pytest.approx(math.radians(30.0))


def test_body_z_to_attitude_level_is_pure_yaw():
    for yaw in (-2.5, 0.0, 0.7, 3.0):
        q = body_z_to_attitude((0.0, 0.0, 1.0), yaw)
        assert quaternion.angle_between(q, quaternion.from_euler(0.0, 0.0, yaw)) < 1e-9


def test_body_z_to_attitude_zero_vector_is_level():
    q = body_z_to_attitude((0.0, 0.0, 0.0), 0.4)
    assert quaternion.angle_between(q, quaternion.from_euler(0.0, 0.0, 0.4)) < 1e-9


@pytest.mark.parametrize("yaw", [0.0, 1.0, -2.0])
@pytest.mark.parametrize("body_z", [(0.3, -0.2, 0.9), (-0.5, 0.1, 0.6), (0.0, 0.6, 0.8)])
def test_body_z_to_attitude_aligns_z_and_heading(body_z, yaw):
    q = body_z_to_attitude(body_z, yaw)
    n = math.sqrt(sum(c * c for c in body_z))
    assert quaternion.dcm_z(q) == pytest.approx(tuple(c / n for c in body_z), abs=1e-12)
    # body_x lies in the vertical plane of the heading: orthogonal to y_C, pointing forward.
    body_x = quaternion.rotate(q, (1.0, 0.0, 0.0))
    y_c = (-math.sin(yaw), math.cos(yaw), 0.0)
    assert sum(a * b for a, b in zip(body_x, y_c, strict=True)) == pytest.approx(0.0, abs=1e-12)
    assert body_x[0] * math.cos(yaw) + body_x[1] * math.sin(yaw) > 0.0


def test_body_z_to_attitude_inverted_keeps_nose_forward():
    q = body_z_to_attitude((0.1, 0.0, -1.0), 0.0)
    assert quaternion.dcm_z(q)[2] < 0.0
    assert quaternion.rotate(q, (1.0, 0.0, 0.0))[0] > 0.0


def test_thrust_to_attitude_reproduces_the_thrust_vector():
    thrust = (0.1, -0.2, -0.6)
    q, thrust_body = thrust_to_attitude(thrust, 0.3)
    assert thrust_body[:2] == (0.0, 0.0)
    assert thrust_body[2] == pytest.approx(-math.sqrt(0.01 + 0.04 + 0.36))
    assert quaternion.rotate(q, thrust_body) == pytest.approx(thrust, abs=1e-12)
