"""Hamilton quaternions ``(w, x, y, z)`` as plain tuples.

Convention (PX4's): ``q`` rotates a vector from the body frame (FRD) to the world frame (NED),
``v_world = rotate(q, v_body)``. Euler angles are the 3-2-1 (yaw, pitch, roll) intrinsic sequence.
"""

from __future__ import annotations

import math

from stack.mathlib.scalar import FLT_EPSILON
from stack.mathlib.vector import Vec3

Quat = tuple[float, float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]

IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)
NAN_QUAT: Quat = (math.nan, math.nan, math.nan, math.nan)
"""What a quaternion that names no rotation (zero, or not finite) normalises to."""


def mul(p: Quat, q: Quat) -> Quat:
    """Hamilton product p ⊗ q."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (
        pw * qw - px * qx - py * qy - pz * qz,
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
    )


def conj(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def inv(q: Quat) -> Quat:
    n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]
    return (q[0] / n2, -q[1] / n2, -q[2] / n2, -q[3] / n2)


def norm(q: Quat) -> float:
    return math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


def normalized(q: Quat) -> Quat:
    """``q`` scaled to unit length; NAN_QUAT when it is zero or not finite."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if not 0.0 < n < math.inf:
        if not is_finite(q):
            return NAN_QUAT
        # The squares of huge components overflow and of tiny ones underflow: scale first.
        m = max(abs(c) for c in q)
        if m == 0.0:
            return NAN_QUAT
        q = (q[0] / m, q[1] / m, q[2] / m, q[3] / m)
        n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def canonical(q: Quat) -> Quat:
    """The representative whose first element beyond FLT_EPSILON is positive (PX4 ``Quaternion::canonical``):
    a scalar part that is rounding noise (a rotation by 180°) does not decide the sign."""
    for c in q:
        if c > FLT_EPSILON:
            return q
        if c < -FLT_EPSILON:
            return (-q[0], -q[1], -q[2], -q[3])
    return q


def is_finite(q: Quat) -> bool:
    return all(math.isfinite(c) for c in q)


def rotate(q: Quat, v: Vec3) -> Vec3:
    """Rotate v by q (body → world for an attitude quaternion)."""
    w, x, y, z = q
    vx, vy, vz = v
    # t = 2 * (q_vec × v)
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def rotate_inv(q: Quat, v: Vec3) -> Vec3:
    """Rotate v by the inverse of q (world → body for an attitude quaternion)."""
    return rotate((q[0], -q[1], -q[2], -q[3]), v)


def dcm_z(q: Quat) -> Vec3:
    """Third column of the rotation matrix: the body z axis expressed in the world frame."""
    w, x, y, z = q
    return (2.0 * (w * y + x * z), 2.0 * (y * z - w * x), w * w - x * x - y * y + z * z)


def to_dcm(q: Quat) -> Mat3:
    """Rotation matrix (rows) R such that v_world = R · v_body."""
    w, x, y, z = q
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    return (
        (ww + xx - yy - zz, 2.0 * (x * y - w * z), 2.0 * (w * y + x * z)),
        (2.0 * (x * y + w * z), ww - xx + yy - zz, 2.0 * (y * z - w * x)),
        (2.0 * (x * z - w * y), 2.0 * (w * x + y * z), ww - xx - yy + zz),
    )


def from_dcm(r: Mat3) -> Quat:
    """Quaternion from a rotation matrix (Shepperd's method, numerically robust)."""
    tr = r[0][0] + r[1][1] + r[2][2]
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q = (0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s)
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2.0
        q = ((r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s)
    elif r[1][1] > r[2][2]:
        s = math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2.0
        q = ((r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s)
    else:
        s = math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2.0
        q = ((r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s)
    return canonical(normalized(q))


def from_euler(roll: float, pitch: float, yaw: float) -> Quat:
    """3-2-1 Euler angles (rad) to quaternion."""
    cr, sr = math.cos(roll * 0.5), math.sin(roll * 0.5)
    cp, sp = math.cos(pitch * 0.5), math.sin(pitch * 0.5)
    cy, sy = math.cos(yaw * 0.5), math.sin(yaw * 0.5)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def to_euler(q: Quat) -> Vec3:
    """Quaternion to 3-2-1 Euler angles (roll, pitch, yaw) in rad."""
    w, x, y, z = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    s = 2.0 * (w * y - z * x)
    pitch = math.copysign(math.pi / 2.0, s) if abs(s) >= 1.0 else math.asin(s)
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return (roll, pitch, yaw)


def yaw(q: Quat) -> float:
    w, x, y, z = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def from_axis_angle(axis: Vec3, angle: float) -> Quat:
    """Rotation of ``angle`` rad about the unit vector ``axis``."""
    s = math.sin(angle * 0.5)
    return (math.cos(angle * 0.5), axis[0] * s, axis[1] * s, axis[2] * s)


def from_rotation_vector(v: Vec3) -> Quat:
    """Exponential map: rotation about v/|v| by |v| rad."""
    angle = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if angle < 1e-10:
        return normalized((1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]))
    s = math.sin(angle * 0.5) / angle
    return (math.cos(angle * 0.5), v[0] * s, v[1] * s, v[2] * s)


def to_rotation_vector(q: Quat) -> Vec3:
    """Logarithmic map: axis × angle (rad) of the canonical form of q."""
    w, x, y, z = canonical(q)
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-10:
        return (2.0 * x, 2.0 * y, 2.0 * z)
    angle = 2.0 * math.atan2(n, w)
    return (x / n * angle, y / n * angle, z / n * angle)


def from_two_vectors(src: Vec3, dst: Vec3, eps: float = 1e-5) -> Quat:
    """Shortest rotation taking the direction of src onto the direction of dst (PX4 ``Quaternion(src, dst)``).

    Opposite directions have no shortest rotation: as PX4, a half turn about src × the basis axis along which
    src is smallest (the first such axis on a tie), so that controllers agree with upstream there too."""
    cr = _cross(src, dst)
    dt = src[0] * dst[0] + src[1] * dst[1] + src[2] * dst[2]
    if math.sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) < eps and dt < 0.0:
        ax, ay, az = abs(src[0]), abs(src[1]), abs(src[2])
        if ax < ay:
            axis = (1.0, 0.0, 0.0) if ax < az else (0.0, 0.0, 1.0)
        else:
            axis = (0.0, 1.0, 0.0) if ay < az else (0.0, 0.0, 1.0)
        cr = _cross(src, axis)
        w = 0.0
    else:
        ns2 = src[0] * src[0] + src[1] * src[1] + src[2] * src[2]
        nd2 = dst[0] * dst[0] + dst[1] * dst[1] + dst[2] * dst[2]
        w = dt + math.sqrt(ns2 * nd2)
    return normalized((w, cr[0], cr[1], cr[2]))


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def integrate(q: Quat, omega_body: Vec3, dt: float) -> Quat:
    """Propagate an attitude by a constant body rate over dt (exact for constant rate)."""
    return normalized(mul(q, from_rotation_vector((omega_body[0] * dt, omega_body[1] * dt, omega_body[2] * dt))))


def angle_between(p: Quat, q: Quat) -> float:
    """Smallest rotation angle (rad) taking p to q."""
    d = abs(p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3])
    return 2.0 * math.acos(min(1.0, d))


def tilt(q: Quat) -> float:
    """Angle [rad] between the body z axis and the world z axis (0 level, π upside down)."""
    return math.acos(max(-1.0, min(1.0, dcm_z(q)[2])))
