"""Geometry helpers of the multicopter position controller (PX4 ``ControlMath``).

Follows ``src/modules/mc_pos_control/PositionControl/ControlMath.cpp``: the horizontal speed limit
that gives the position-error term priority over the feed-forward (``constrainXY``), the tilt
limit (``limitTilt``) and the conversion of a thrust direction plus yaw into an attitude
setpoint (``bodyzToAttitude`` / ``thrustToAttitude``). Vectors are NED tuples, quaternions
Hamilton (w, x, y, z) body → world.
"""

from __future__ import annotations

import math

from stack.mathlib import quaternion
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3

Vec2 = tuple[float, float]

_MIN_LENGTH = 0.001


def add_if_not_nan(setpoint: float, addition: float) -> float:
    """Add a control contribution to a setpoint, treating NaN as "absent".

    Both finite: their sum. Setpoint NaN: the addition (NaN or not). Addition NaN: the setpoint.
    """
    if math.isfinite(setpoint):
        return setpoint + addition if math.isfinite(addition) else setpoint
    return addition


def constrain_xy(v0: Vec2, v1: Vec2, max_norm: float) -> Vec2:
    """Limit |v0 + v1| to max_norm, giving v0 priority over v1 (PX4 ``ControlMath::constrainXY``).

    v0 is the part that must be kept (the position-error term), v1 the part that may be scaled
    (the feed-forward). If the sum is too long: v0 alone already too long → v0 scaled to max_norm;
    otherwise v0 + s·v1/|v1| with s ≥ 0 solving |v0 + s·u1| = max_norm. NaN in v1 propagates.
    """
    sx = v0[0] + v1[0]
    sy = v0[1] + v1[1]
    if math.hypot(sx, sy) <= max_norm:
        return (sx, sy)
    if max_norm <= 0.0:
        return (0.0, 0.0)
    n0 = math.hypot(v0[0], v0[1])
    if n0 >= max_norm:
        return (v0[0] / n0 * max_norm, v0[1] / n0 * max_norm)
    n1 = math.hypot(v1[0], v1[1])
    if n1 < _MIN_LENGTH:
        return (v0[0] / n0 * max_norm, v0[1] / n0 * max_norm)
    if n0 < _MIN_LENGTH:
        return (v1[0] / n1 * max_norm, v1[1] / n1 * max_norm)
    # |v0 + s·u1|² = max² is s² + 2·m·s + c = 0 with m = u1·v0, c = |v0|² − max² < 0,
    # so the positive root always exists.
    ux = v1[0] / n1
    uy = v1[1] / n1
    m = ux * v0[0] + uy * v0[1]
    c = n0 * n0 - max_norm * max_norm
    s = -m + math.sqrt(m * m - c)
    return (v0[0] + ux * s, v0[1] + uy * s)


def limit_tilt(body_unit: Vec3, world_unit: Vec3, max_angle: float) -> Vec3:
    """Rotate the unit vector body_unit toward world_unit until their angle is ≤ max_angle (rad).

    PX4 ``ControlMath::limitTilt``: the result lies in the plane spanned by both vectors. If they
    are exactly (anti-)parallel the rotation plane is chosen through world x. NaN propagates.
    """
    bx, by, bz = body_unit
    wx, wy, wz = world_unit
    d = bx * wx + by * wy + bz * wz
    if d > 1.0:
        d = 1.0
    elif d < -1.0:
        d = -1.0
    angle = math.acos(d)
    if angle > max_angle:
        angle = max_angle
    rx = bx - d * wx
    ry = by - d * wy
    rz = bz - d * wz
    rn2 = rx * rx + ry * ry + rz * rz
    if rn2 < FLT_EPSILON:
        rx = 1.0
        rn2 = rx * rx + ry * ry + rz * rz
    rn = math.sqrt(rn2)
    c = math.cos(angle)
    s = math.sin(angle) / rn
    return (c * wx + s * rx, c * wy + s * ry, c * wz + s * rz)


def body_z_to_attitude(body_z: Vec3, yaw: float) -> Quat:
    """Attitude whose body z axis points along body_z (NED) with heading yaw (PX4 ``bodyzToAttitude``).

    body_x = y_C × body_z with y_C = (−sin ψ, cos ψ, 0), negated when inverted (body_z up) so the
    nose stays forward; body_y = body_z × body_x. A zero body_z means level; a horizontal body_z
    (no defined heading) takes body_x = world down.
    """
    zx, zy, zz = body_z
    if zx * zx + zy * zy + zz * zz < FLT_EPSILON:
        zz = 1.0
    n = math.sqrt(zx * zx + zy * zy + zz * zz)
    zx /= n
    zy /= n
    zz /= n

    ycx = -math.sin(yaw)
    ycy = math.cos(yaw)
    # y_C × body_z with y_C[2] = 0
    xx = ycy * zz
    xy = -ycx * zz
    xz = ycx * zy - ycy * zx
    if zz < 0.0:
        xx, xy, xz = -xx, -xy, -xz
    if abs(zz) < 1e-6:
        xx, xy, xz = 0.0, 0.0, 1.0
    n = math.sqrt(xx * xx + xy * xy + xz * xz)
    xx /= n
    xy /= n
    xz /= n

    yx = zy * xz - zz * xy
    yy = zz * xx - zx * xz
    yz = zx * xy - zy * xx
    return quaternion.from_dcm(((xx, yx, zx), (xy, yy, zy), (xz, yz, zz)))


def thrust_to_attitude(thrust_ned: Vec3, yaw: float) -> tuple[Quat, Vec3]:
    """Attitude setpoint and body thrust from a NED thrust vector (PX4 ``thrustToAttitude``).

    The body z axis is aligned with −thrust; returns (q_d, thrust_body = (0, 0, −|T|)).
    """
    tx, ty, tz = thrust_ned
    q_d = body_z_to_attitude((-tx, -ty, -tz), yaw)
    return q_d, (0.0, 0.0, -math.sqrt(tx * tx + ty * ty + tz * tz))
