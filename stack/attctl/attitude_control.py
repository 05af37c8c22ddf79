"""Multicopter attitude P controller: attitude error → body-rate setpoint.

Follows PX4 ``mc_att_control/AttitudeControl/AttitudeControl.cpp`` (the tilt-prioritised quaternion
law of Brescianini, Hehn and D'Andrea, "Nonlinear Quadrocopter Attitude Control", ETH 2013): the
thrust axis is corrected along the shortest path first and the yaw remainder is scaled down by
MC_YAW_WEIGHT, with the yaw gain divided by the same weight so small yaw errors keep gain MC_YAW_P.

``attitude_error_dcm`` is the older PX4 rotation-matrix formulation of the same idea (``control_attitude`` in
``mc_att_control_main.cpp`` before 2016), kept for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.param import Param


class AttitudeControlParams(ParamSet):
    """The attitude loop's P gains, yaw weight and body-rate limits (the catalogue's MC_*)."""

    mc_roll_p: float
    mc_pitch_p: float
    mc_yaw_p: float
    mc_yaw_weight: float
    mc_rollrate_max: float
    mc_pitchrate_max: float
    mc_yawrate_max: float


PARAMS: tuple[Param, ...] = AttitudeControlParams.PARAMS

_AXIS_DEGENERATE = 1.0 - 1e-5


class AttitudeControl:
    """PX4's AttitudeControl: ``set_attitude_setpoint`` then ``update(q)`` → body-rate setpoint [rad/s].

    Quaternions are Hamilton (w, x, y, z), body FRD → world NED.
    """

    __slots__ = ("_gain", "_q_sp", "_rate_limit", "_yaw_weight", "_yawspeed_sp")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._gain: Vec3 = (0.0, 0.0, 0.0)
        self._yaw_weight = 1.0
        self._rate_limit: Vec3 = (0.0, 0.0, 0.0)
        self._q_sp: Quat = quat.IDENTITY
        self._yawspeed_sp = 0.0
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        """Apply MC_ROLL_P, MC_PITCH_P, MC_YAW_P, MC_YAW_WEIGHT and MC_*RATE_MAX (missing → PX4 default)."""
        p = AttitudeControlParams.from_params(params)
        self.set_gains((p.mc_roll_p, p.mc_pitch_p, p.mc_yaw_p),
                       p.mc_yaw_weight)
        self.set_rate_limits(tuple(math.radians(r) for r in (p.mc_rollrate_max, p.mc_pitchrate_max, p.mc_yawrate_max)))

    def set_gains(self, proportional_gain: Vec3, yaw_weight: float) -> None:
        """P gains (roll, pitch, yaw) [1/s] and the yaw weight in [0, 1]; the yaw gain is divided by the
        weight so that the small-angle yaw gain stays ``proportional_gain[2]``."""
        w = min(max(yaw_weight, 0.0), 1.0)
        self._yaw_weight = w
        kz = proportional_gain[2] / w if w > 1e-4 else proportional_gain[2]
        self._gain = (proportional_gain[0], proportional_gain[1], kz)

    def set_rate_limits(self, rate_limit: Vec3) -> None:
        """Per-axis rate setpoint limits [rad/s]."""
        self._rate_limit = (rate_limit[0], rate_limit[1], rate_limit[2])

    def set_attitude_setpoint(self, q_sp: Quat, yawspeed_setpoint: float = math.nan) -> None:
        """Desired attitude and the yaw feed-forward ``yaw_sp_move_rate`` [rad/s about world z; NaN = none].
        A ``q_sp`` that names no rotation (zero or not finite) is dropped: the previous setpoint stays."""
        q_sp = quat.normalized(q_sp)
        if quat.is_finite(q_sp):
            self._q_sp = q_sp
        self._yawspeed_sp = yawspeed_setpoint

    @property
    def attitude_setpoint(self) -> Quat:
        return self._q_sp

    def adapt_to_reset(self, delta_q: Quat) -> None:
        """Shift the setpoint by an estimator reset (``q_new = delta_q ⊗ q_old``, e.g. a heading reset)."""
        q_sp = quat.normalized(quat.mul(delta_q, self._q_sp))
        if quat.is_finite(q_sp):
            self._q_sp = q_sp

    def update(self, q: Quat) -> Vec3:
        """Body-rate setpoint [rad/s] that moves attitude ``q`` toward the setpoint; NaN (the rate controller's
        "hold the current rate") when ``q`` names no rotation."""
        q = quat.normalized(q)
        qw, qx, qy, qz = q
        if qw != qw:
            return (math.nan, math.nan, math.nan)
        qd = self._q_sp
        # Reduced setpoint: rotate the current thrust axis onto the desired one, keep the current yaw.
        q_red = quat.from_two_vectors(quat.dcm_z(q), quat.dcm_z(qd))
        degenerate = abs(q_red[1]) > _AXIS_DEGENERATE or abs(q_red[2]) > _AXIS_DEGENERATE
        q_red = qd if degenerate else quat.mul(q_red, q)
        # Remaining rotation about z, scaled by the yaw weight.
        dw, _, _, dz = quat.canonical(quat.mul(quat.conj(q_red), qd))
        dw = min(max(dw, -1.0), 1.0)
        dz = min(max(dz, -1.0), 1.0)
        w = self._yaw_weight
        q_yaw = (math.cos(w * math.acos(dw)), 0.0, 0.0, math.sin(w * math.asin(dz)))
        qd_weighted = quat.mul(q_red, q_yaw)
        # Error quaternion q⁻¹ ⊗ qd; 2·imag of its canonical form is 2·sin(α/2)·axis on the short way round.
        _, ex, ey, ez = quat.canonical(quat.mul((qw, -qx, -qy, -qz), qd_weighted))
        kx, ky, kz = self._gain
        rx, ry, rz = 2.0 * ex * kx, 2.0 * ey * ky, 2.0 * ez * kz
        yawspeed = self._yawspeed_sp
        if math.isfinite(yawspeed):
            # World z expressed in the body frame (third column of Rᵀ).
            rx += 2.0 * (qx * qz - qw * qy) * yawspeed
            ry += 2.0 * (qw * qx + qy * qz) * yawspeed
            rz += (qw * qw - qx * qx - qy * qy + qz * qz) * yawspeed
        lx, ly, lz = self._rate_limit
        return (
            lx if rx > lx else -lx if rx < -lx else rx,
            ly if ry > ly else -ly if ry < -ly else ry,
            lz if rz > lz else -lz if rz < -lz else rz,
        )


def attitude_error_dcm(q: Quat, q_sp: Quat) -> Vec3:
    """Attitude error vector [rad, body frame] of PX4's original rotation-matrix controller.

    The thrust axis error is an axis·angle (angle, not 2·sin(α/2)); the yaw error, measured after the
    tilt-only rotation R_rp, is weighted by yaw_w = R_sp(2,2)² (no yaw control with a horizontal thrust
    axis). For thrust-axis errors beyond 90° the result is blended with the direct R → R_sp rotation
    with weight cos²·yaw_w. Rate setpoint = (MC_ROLL_P, MC_PITCH_P, MC_YAW_P) ∘ error.

    Upstream scaled the direct rotation by 2·atan2(|v|, w) *after* normalising v (so |v| = 1); this
    uses the rotation's true angle, which is what that line was meant to compute.
    """
    r = quat.to_dcm(q)
    r_sp = quat.to_dcm(q_sp)
    r_z = (r[0][2], r[1][2], r[2][2])
    r_sp_z = (r_sp[0][2], r_sp[1][2], r_sp[2][2])
    # Axis and sin(angle) of the rotation taking R_z onto R_sp_z, in the body frame.
    c = (r_z[1] * r_sp_z[2] - r_z[2] * r_sp_z[1],
         r_z[2] * r_sp_z[0] - r_z[0] * r_sp_z[2],
         r_z[0] * r_sp_z[1] - r_z[1] * r_sp_z[0])
    e = tuple(r[0][i] * c[0] + r[1][i] * c[1] + r[2][i] * c[2] for i in range(3))
    sin_z = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    cos_z = r_z[0] * r_sp_z[0] + r_z[1] * r_sp_z[1] + r_z[2] * r_sp_z[2]
    yaw_w = r_sp[2][2] * r_sp[2][2]
    if sin_z > 0.0:
        angle = math.atan2(sin_z, cos_z)
        axis = (e[0] / sin_z, e[1] / sin_z, e[2] / sin_z)
        e = (axis[0] * angle, axis[1] * angle, axis[2] * angle)
        r_rp = quat.to_dcm(quat.mul(q, quat.from_axis_angle(axis, angle)))
    else:
        r_rp = r
    # R_rp and R_sp share their z axis; the yaw error is the angle between their x axes about it.
    sp_x = (r_sp[0][0], r_sp[1][0], r_sp[2][0])
    rp_x = (r_rp[0][0], r_rp[1][0], r_rp[2][0])
    cx = (rp_x[1] * sp_x[2] - rp_x[2] * sp_x[1],
          rp_x[2] * sp_x[0] - rp_x[0] * sp_x[2],
          rp_x[0] * sp_x[1] - rp_x[1] * sp_x[0])
    yaw_err = math.atan2(cx[0] * r_sp_z[0] + cx[1] * r_sp_z[1] + cx[2] * r_sp_z[2],
                         rp_x[0] * sp_x[0] + rp_x[1] * sp_x[1] + rp_x[2] * sp_x[2]) * yaw_w
    ex, ey, ez = e[0], e[1], yaw_err
    if cos_z < 0.0:
        direct = quat.to_rotation_vector(quat.mul(quat.conj(q), q_sp))
        direct_w = cos_z * cos_z * yaw_w
        ex = ex * (1.0 - direct_w) + direct[0] * direct_w
        ey = ey * (1.0 - direct_w) + direct[1] * direct_w
        ez = ez * (1.0 - direct_w) + direct[2] * direct_w
    return (ex, ey, ez)
