"""Local position Kalman filter in the spirit of PX4's LPE (``src/modules/local_position_estimator``).

A linear Kalman filter with 10 states::

    x, y, z        position NED about the reference point [m]
    vx, vy, vz     velocity NED [m/s]
    bx, by, bz     accelerometer bias, body FRD [m/s²]
    hgt_offset     offset of the secondary height sensor [m]

Prediction integrates the accelerometer specific force, rotated to NED by the attitude estimate,
plus gravity: ``a = R(q)·(f − b) + (0, 0, g)``. The bias is kept in the body frame, like LPE,
because an accelerometer bias is a property of the sensor: it stays constant while the vehicle yaws,
whereas its NED image would rotate with every heading change and could only be followed through
process noise. The price is a state-dependent transition matrix, rebuilt every step from ``R``.

Height reference (EKF2's ``EKF2_HGT_REF``): one height sensor defines z, the other one measures
z through an offset state, so that it can correct the absolute altitude without moving z.

- ``EKF2_HGT_REF = 0`` (barometer, default here): z is referenced to the first baro sample (the
  ground at start) for the whole flight. Once GPS sets the origin, the offset state is the GPS
  altitude minus the baro-referenced altitude, a random walk (``LPE_PN_GPS_Z``) learnt from GPS
  altitude; the barometer has no offset. The GPS altitude row of the joint GPS update is
  ``z − offset``: its noise goes to the offset, not to z. The published reference altitude is
  ``baro reference + offset``, so ``alt = ref_alt − z`` is the GPS-corrected absolute altitude, and
  ``ref_alt`` follows the offset estimate slowly. Without a baro at start, GPS defines z until the
  first baro sample, which then takes over with z continuous (the GPS frame becomes the offset).
- ``EKF2_HGT_REF = 1`` (GPS): the offset state is the baro altitude minus the estimated altitude
  (random walk ``LPE_PN_BARO``). Until GPS sets the global origin, z is referenced to the first baro
  sample and the offset is frozen at 0; afterwards GPS altitude defines absolute height and the
  baro smooths it.

Corrections:

- GPS position (lat/lon projected with :class:`stack.mathlib.geo.MapProjection`, altitude against
  the reference altitude) and NED velocity. Each sample is fused at its measurement time
  ``timestamp_sample − LPE_GPS_DELAY``: the filter keeps the states, covariances and inputs of the
  last 0.5 s (LPE's ``GPS_DELAY_MAX``), rolls back to the step at the measurement time, fuses there
  and re-runs the later predictions and baro fusions. This is the exact linear-KF answer, unlike
  LPE, which only computes the residual against the delayed state and applies it to the current one.
- Barometer altitude, fused at arrival (PX4's baro delay is 0).
- The land detector: while landed and at rest, zero horizontal velocity (LPE's land measurement, fused
  when EKF2 fuses zero velocity).
- Airspeed while GPS is lost (a plane's dead reckoning, as EKF2 fuses airspeed with its wind states): the
  true airspeed along the body x axis plus the wind estimate is the horizontal velocity, so the velocity
  error stays that of the wind estimate instead of growing with the integrated accelerometer error.
- Gates: EKF2-style innovation tests per group (horizontal position, vertical position,
  horizontal velocity, vertical velocity, baro): a group is fused when every component satisfies
  ``r² ≤ gate²·S``. A group that has been rejected for longer than 7 s (EKF2's
  ``reset_timeout_max``) is reset to the measurement, with PX4-style reset counters and deltas. With
  the baro reference a rejected baro resets z (the offset moves with it, so the global altitude does
  not jump) and a rejected GPS altitude resets the offset, not z; with the GPS reference a rejected
  baro resets its offset while GPS height is fused, else z.

The origin (ref lat/lon) is set at the 10th consecutive GPS fix passing LPE's initialisation
checks (3-D fix, ≥ 6 satellites, eph ≤ LPE_EPH_MAX, epv ≤ LPE_EPV_MAX): the horizontal position is
reset to zero there and the velocity to the GPS velocity; z does not jump.

Parameters, in :class:`PositionEstimatorParams` (defined in :mod:`stack.params.lpe` and
:mod:`stack.params.ekf2`). LPE names carry PX4's LPE defaults.
Additions, with the reason:

- ``EKF2_HGT_REF`` 0 (barometer): the height reference, see above. PX4 also offers 2 (range
  finder) and 3 (vision), which this filter has no sensor for. Like PX4 (``reboot_required``), a
  change takes effect at the next :meth:`LocalPositionKF.reset`.
- ``LPE_XY_PUB`` 2.0 m: eph (``sqrt(Pxx + Pyy)``) above which ``xy_valid`` is cleared. LPE hard-codes
  this 2 m (``EST_STDDEV_XY_VALID``); it is exposed beside LPE's own ``LPE_VXY_PUB``/``LPE_Z_PUB``.
  (PX4's ``LPE_X_LP`` is not an eph limit: it is the 5 Hz low-pass LPE applies to its published
  state, which this filter does not add, so as not to delay the position controller.)
- ``LPE_PN_BARO`` 0.01 m/s/√Hz: random walk of the baro offset (GPS reference), a state LPE does not
  have. EKF2 uses 0.13 (its compiled-in ``baro_bias_nsd``); a smaller value keeps the absolute height
  from wandering with LPE's coarse GPS altitude weighting.
- ``LPE_PN_GPS_Z`` 0.13 m/s/√Hz: random walk of the GPS altitude offset (baro reference), EKF2's
  compiled-in ``gps_hgt_bias_nsd``. A separate name because it is a different sensor's error: GNSS
  altitude wanders by metres over minutes, and the offset must follow that so that it, and not z,
  absorbs the GPS altitude error.
- ``LPE_PN_VZ`` 0.1 m/s²/√Hz: the velocity propagation noise of the vertical axis, which LPE takes
  from ``LPE_PN_V`` like the horizontal ones (the same 0.1 by default). The unmodelled acceleration
  that noise stands for is mostly the attitude error tilting gravity into the accelerometer: g·δ
  horizontally but only g·δ²/2 vertically, so a vehicle whose accelerometer has no vibration can hold
  a far smaller vertical figure, and the height estimate then averages its barometer over longer.
- ``EKF2_GPS_P_GATE``, ``EKF2_GPS_V_GATE``, ``EKF2_BARO_GATE``, ``EKF2_TAS_GATE`` 5 σ: LPE has no
  configurable gate (it only flags a fault at a fixed χ² level and fuses anyway), so EKF2's gates are used.
- ``LPE_AIRSPD_VXY`` 1.0 m/s: LPE fuses no airspeed. The standard deviation, per axis, of the horizontal
  velocity that airspeed and wind give, beyond the wind estimate's own variance: the angle of attack and
  sideslip the body axis ignores, the airspeed sensor's error. Fused only without GPS (with it, GPS
  velocity is far better); 0 turns it off.
- ``EKF2_ABL_LIM`` 0.4 m/s² and ``EKF2_ABIAS_INIT`` 0.2 m/s²: accelerometer bias limit and initial
  uncertainty. LPE hard-codes 0.1 m/s² and 1e-3 m/s², which all but freezes the bias.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet
from stack.params.ekf2 import HGT_REF_BARO, HGT_REF_GPS

PERIOD_US = 20_000
"""The estimator's step: it predicts and fuses at 50 Hz."""

N_X = 10
X_X, X_Y, X_Z, X_VX, X_VY, X_VZ, X_BX, X_BY, X_BZ, X_HGT_OFS = range(N_X)

class PositionEstimatorParams(ParamSet):
    """The LPE_* and EKF2_* parameters the filter reads (the catalogue's, see the module docstring)."""

    ekf2_hgt_ref: int
    lpe_gps_xy: float
    lpe_gps_z: float
    lpe_gps_vxy: float
    lpe_gps_vz: float
    lpe_gps_delay: float
    lpe_bar_z: float
    lpe_acc_xy: float
    lpe_acc_z: float
    lpe_pn_p: float
    lpe_pn_v: float
    lpe_pn_vz: float
    lpe_pn_b: float
    lpe_pn_baro: float
    lpe_pn_gps_z: float
    lpe_land_vxy: float
    lpe_airspd_vxy: float
    lpe_eph_max: float
    lpe_epv_max: float
    lpe_xy_pub: float
    lpe_vxy_pub: float
    lpe_z_pub: float
    ekf2_gps_p_gate: float
    ekf2_gps_v_gate: float
    ekf2_baro_gate: float
    ekf2_tas_gate: float
    ekf2_abl_lim: float
    ekf2_abias_init: float



_HVEL_ROWS = np.array((X_VX, X_VY))
GPS_DELAY_MAX_US = 500_000  # LPE: history length; older measurements are dropped
GPS_TIMEOUT_US = 1_000_000  # LPE: no horizontal GPS fusion for this long = dead reckoning
GPS_INIT_COUNT = 10  # LPE REQ_GPS_INIT_COUNT
GPS_INIT_MIN_SATS = 6  # LPE
GPS_FIX_3D = 3
FUSION_RESET_TIMEOUT_US = 7_000_000  # EKF2 reset_timeout_max
P_MAX = 1e6  # LPE: a variance above this stops growing
DT_MAX_S = 0.05
ACCEL_MAX = 16.0 * CONSTANTS_ONE_G  # full scale of a typical flight-controller IMU
ALT_MIN_M, ALT_MAX_M = -1000.0, 20000.0  # plausible AMSL altitudes of a multicopter sensor
AIRSPEED_MAX = 150.0  # m/s: beyond any airframe this filter serves

# Innovation groups of a GPS sample: (rows of the measurement vector, gate parameter).
_GPS_GROUPS = (
    ((0, 1), "ekf2_gps_p_gate"),
    ((2,), "ekf2_gps_p_gate"),
    ((3, 4), "ekf2_gps_v_gate"),
    ((5,), "ekf2_gps_v_gate"),
)
_G_HPOS, _G_VPOS, _G_HVEL, _G_VVEL = range(4)
_ROW_ALT = 2  # GPS measurement row of the altitude

# Flat indices in a 10×10 matrix of the transition entries that change with dt and the attitude:
# ∂p/∂v (dt), then ∂p/∂b (−½dt²·R) and ∂v/∂b (−dt·R), row by row.
_F_VARIABLE = np.array(
    [X_X * N_X + X_VX, X_Y * N_X + X_VY, X_Z * N_X + X_VZ]
    + [row * N_X + col for row in (X_X, X_Y, X_Z, X_VX, X_VY, X_VZ) for col in (X_BX, X_BY, X_BZ)]
)
_IDENTITY = np.identity(N_X)


class GpsMeasurement(Protocol):
    """What :meth:`LocalPositionKF.fuse_gps` reads; ``stack.msg.sensors.SensorGps`` satisfies it."""

    timestamp_sample: int  # µs, time the fix was valid at the receiver
    latitude_deg: float
    longitude_deg: float
    altitude_msl_m: float
    vel_n_m_s: float
    vel_e_m_s: float
    vel_d_m_s: float
    vel_ned_valid: bool
    eph: float  # m, 1σ; NaN = not reported
    epv: float  # m, 1σ; NaN = not reported
    fix_type: int
    satellites_used: int


@dataclass(slots=True)
class LocalPositionEstimate:
    """The filter output, shaped like PX4's ``vehicle_local_position`` (plus the global position)."""

    timestamp_sample: int  # µs, time of the last prediction
    position: Vec3  # m, NED about the reference point
    velocity: Vec3  # m/s, NED
    acceleration: Vec3  # m/s², NED, bias-corrected, gravity removed
    xy_valid: bool
    z_valid: bool
    v_xy_valid: bool
    v_z_valid: bool
    eph: float  # m, 1σ horizontal position
    epv: float  # m, 1σ vertical position (z, in the frame of the height reference)
    evh: float  # m/s, 1σ horizontal velocity
    evv: float  # m/s, 1σ vertical velocity
    dead_reckoning: bool  # horizontal aiding was lost: xy comes from the IMU alone
    xy_global: bool  # the reference lat/lon is set
    z_global: bool  # ref_alt is a GPS-based AMSL altitude (the origin is set)
    ref_timestamp: int  # µs, measurement time of the fix that set the origin (0 = not set)
    ref_lat: float  # deg (NaN until set)
    ref_lon: float  # deg
    ref_alt: float  # m AMSL of z = 0 (NaN until z is initialised; moves with the GPS offset, baro reference)
    lat: float  # deg, global position (NaN until the origin is set)
    lon: float  # deg
    alt: float  # m AMSL, ref_alt − z
    delta_xy: tuple[float, float]  # m, jump of the last xy reset
    xy_reset_counter: int  # counts every reset (PX4 publishes it modulo 256)
    delta_z: float
    z_reset_counter: int
    delta_vxy: tuple[float, float]
    vxy_reset_counter: int
    delta_vz: float
    vz_reset_counter: int
    delta_alt: float  # m, jump of alt at its last reset (vehicle_global_position.delta_alt)
    alt_reset_counter: int  # resets that made alt jump: z resets, or GPS offset resets (baro reference)
    accel_bias: Vec3  # m/s², body FRD
    baro_offset: float  # m, baro altitude minus alt (0 until both height sensors are in use)


class _Step:
    """One entry of the history: the event that moved the filter to (x, P) at time t_us — a
    prediction (transition F, dt, NED specific force plus gravity, rotation), a baro fusion, a
    horizontal velocity fusion (landed, or airspeed and wind: north, east and their variances), or
    neither (the start of the history)."""

    __slots__ = ("P", "baro_alt", "prediction", "t_us", "velocity", "x")

    def __init__(self, t_us: int, x: np.ndarray, P: np.ndarray) -> None:
        self.t_us = t_us
        self.x = x
        self.P = P
        self.prediction: tuple[np.ndarray, float, float, float, float, quat.Mat3] | None = None
        self.baro_alt: float | None = None
        self.velocity: tuple[float, float, float, float] | None = None


def _step_time(step: _Step) -> int:
    return step.t_us


class LocalPositionKF:
    """Position/velocity/accel-bias/height-offset Kalman filter fusing IMU, GPS and barometer.

    Call :meth:`predict` for every IMU sample (or with averaged samples at a lower rate), and
    :meth:`fuse_gps` / :meth:`fuse_baro` when those arrive. Arrays in the history are never
    modified in place, so a past step can be restored by reference.
    """

    __slots__ = (
        "P",
        "_abl_lim",
        "_accel_ned",
        "_baro_initialised",
        "_gps_init_count",
        "_hgt_ref",
        "_hist",
        "_last_baro_fused_us",
        "_last_fused_us",
        "_last_gps_meas_us",
        "_map",
        "_q_c",
        "_q_dt",
        "_q_dt_s",
        "_ref_alt",
        "_ref_timestamp",
        "_t_us",
        "_z_initialised",
        "alt_reset_counter",
        "baro_test_ratio",
        "delta_alt",
        "delta_vxy",
        "delta_vz",
        "delta_xy",
        "delta_z",
        "gps_pos_test_ratio",
        "gps_vel_test_ratio",
        "params",
        "vxy_reset_counter",
        "vz_reset_counter",
        "x",
        "xy_reset_counter",
        "z_reset_counter",
    )

    def __init__(self, params: PositionEstimatorParams | None = None) -> None:
        self._map: MapProjection | None = None
        self._hgt_ref = HGT_REF_BARO
        self._baro_initialised = False
        self.set_params(params or PositionEstimatorParams())
        self.reset()

    def set_params(self, params: PositionEstimatorParams) -> None:
        """Take new parameters; ``EKF2_HGT_REF`` applies from the next :meth:`reset`."""
        self.params = params
        self._abl_lim = params.ekf2_abl_lim
        self._update_process_noise()

    def reset(self) -> None:
        """Return to the power-on state: no time base, no altitude reference, no origin."""
        p = self.params
        self._hgt_ref = int(p.ekf2_hgt_ref)
        self.x = np.zeros(N_X)
        self.P = np.diag(
            [8.0, 8.0, 8.0]  # LPE: twice its 2 m validity limit, squared
            + [2.0 * p.lpe_vxy_pub**2] * 3
            + [p.ekf2_abias_init**2] * 3
            + [0.0]
        )
        self._t_us: int | None = None
        self._hist: deque[_Step] = deque()
        self._accel_ned: Vec3 = (0.0, 0.0, 0.0)
        self._map = None
        self._ref_alt = math.nan
        self._ref_timestamp = 0
        self._z_initialised = False
        self._baro_initialised = False
        self._gps_init_count = 0
        self._last_gps_meas_us: int | None = None
        self._last_fused_us = [0, 0, 0, 0]  # per GPS group
        self._last_baro_fused_us = 0
        self.xy_reset_counter = self.z_reset_counter = self.vxy_reset_counter = self.vz_reset_counter = 0
        self.alt_reset_counter = 0
        self.delta_xy = (0.0, 0.0)
        self.delta_vxy = (0.0, 0.0)
        self.delta_z = self.delta_vz = self.delta_alt = 0.0
        self.gps_pos_test_ratio = self.gps_vel_test_ratio = self.baro_test_ratio = 0.0
        self._update_process_noise()

    def snapshot(self) -> dict[str, object]:
        """The estimate and its frame (state, covariance, origin, height reference), as JSON-able values, for an
        instance restarted after a crash to :meth:`resume` from."""
        origin = [self._map.lat0_deg, self._map.lon0_deg] if self._map is not None else None
        return {
            "x": self.x.tolist(),
            "P": self.P.tolist(),
            "origin": origin,
            "ref_alt": self._ref_alt,
            "ref_timestamp": self._ref_timestamp,
            "z_initialised": self._z_initialised,
            "baro_initialised": self._baro_initialised,
            "hgt_ref": self._hgt_ref,
        }

    def resume(self, snap: dict[str, object]) -> None:
        """Carry on from a :meth:`snapshot` in the same frame (the time base restarts with the next sample).
        Raises ValueError, changing nothing, if ``snap`` is not one."""
        try:
            x = np.array(snap["x"], dtype=float)
            P = np.array(snap["P"], dtype=float)
            origin = snap["origin"]
            ref_alt = float(snap["ref_alt"])  # type: ignore[arg-type]
            ref_timestamp = int(snap["ref_timestamp"])  # type: ignore[call-overload]
            hgt_ref = int(snap["hgt_ref"])  # type: ignore[call-overload]
            flags = (snap["z_initialised"], snap["baro_initialised"])
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"not a snapshot: {e}") from None
        if x.shape != (N_X,) or P.shape != (N_X, N_X) or not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise ValueError("not a snapshot: the state or covariance has the wrong shape or is not finite")
        if origin is not None and not (isinstance(origin, list) and len(origin) == 2):
            raise ValueError(f"not a snapshot: origin {origin!r}")
        if not all(isinstance(f, bool) for f in flags) or hgt_ref not in (HGT_REF_BARO, HGT_REF_GPS):
            raise ValueError("not a snapshot: flags")
        self.reset()
        self.x, self.P = x, P
        self._map = MapProjection(float(origin[0]), float(origin[1])) if origin is not None else None
        self._ref_alt, self._ref_timestamp, self._hgt_ref = ref_alt, ref_timestamp, hgt_ref
        self._z_initialised, self._baro_initialised = flags

    @property
    def hgt_ref(self) -> int:
        """The height reference in use (``HGT_REF_BARO`` or ``HGT_REF_GPS``), latched at reset."""
        return self._hgt_ref

    def _gps_alt_has_offset(self) -> bool:
        """GPS altitude is measured through the offset state (baro reference, baro in use)."""
        return self._hgt_ref == HGT_REF_BARO and self._baro_initialised

    # ------------------------------------------------------------------ prediction

    def predict(self, timestamp_sample_us: int, accel_body: Vec3, q: Quat) -> bool:
        """Propagate to ``timestamp_sample_us`` with the specific force ``accel_body`` [m/s², FRD]
        held since the previous call and the attitude ``q`` (body → NED).

        Returns False (state untouched) for a non-finite or out-of-range input or a timestamp that
        does not advance. The first call only starts the time base.
        """
        ax, ay, az = accel_body
        if not (math.isfinite(ax) and math.isfinite(ay) and math.isfinite(az)):
            return False
        if ax * ax + ay * ay + az * az > ACCEL_MAX * ACCEL_MAX:
            return False
        if not quat.is_finite(q):
            return False
        q_norm = quat.norm(q)
        if not 0.5 < q_norm < 2.0:
            return False
        t_prev = self._t_us
        if t_prev is None:
            self._t_us = timestamp_sample_us
            self._hist.append(_Step(timestamp_sample_us, self.x, self.P))
            return True
        if timestamp_sample_us <= t_prev:
            return False
        dt = min((timestamp_sample_us - t_prev) * 1e-6, DT_MAX_S)
        self._t_us = timestamp_sample_us

        r = quat.to_dcm(quat.normalized(q))
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = r
        # Specific force in NED plus gravity, before the bias correction.
        an = r00 * ax + r01 * ay + r02 * az
        ae = r10 * ax + r11 * ay + r12 * az
        ad = r20 * ax + r21 * ay + r22 * az + CONSTANTS_ONE_G
        h = -0.5 * dt * dt
        g = -dt
        F = _IDENTITY.copy()
        F.ravel()[_F_VARIABLE] = (
            dt, dt, dt,
            h * r00, h * r01, h * r02, h * r10, h * r11, h * r12, h * r20, h * r21, h * r22,
            g * r00, g * r01, g * r02, g * r10, g * r11, g * r12, g * r20, g * r21, g * r22,
        )
        prediction = (F, dt, an, ae, ad, r)
        x, self.P = self._propagate(self.x, self.P, prediction)
        self.x = x
        bx, by, bz = x[X_BX : X_BZ + 1].tolist()
        self._accel_ned = (
            an - (r00 * bx + r01 * by + r02 * bz),
            ae - (r10 * bx + r11 * by + r12 * bz),
            ad - (r20 * bx + r21 * by + r22 * bz),
        )

        step = _Step(timestamp_sample_us, x, self.P)
        step.prediction = prediction
        hist = self._hist
        hist.append(step)
        oldest = timestamp_sample_us - GPS_DELAY_MAX_US
        while hist[0].t_us < oldest:
            hist.popleft()
        return True

    def _propagate(
        self,
        x: np.ndarray,
        P: np.ndarray,
        prediction: tuple[np.ndarray, float, float, float, float, quat.Mat3],
    ) -> tuple[np.ndarray, np.ndarray]:
        """One prediction step: the state in plain floats (its transition is a few products), the
        covariance as ``F·P·Fᵀ + Q·dt`` with LPE's cap on run-away variances."""
        F, dt, an, ae, ad, r = prediction
        px, py, pz, vx, vy, vz, bx, by, bz, ofs = x.tolist()
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = r
        cn = an - (r00 * bx + r01 * by + r02 * bz)
        ce = ae - (r10 * bx + r11 * by + r12 * bz)
        cd = ad - (r20 * bx + r21 * by + r22 * bz)
        h = 0.5 * dt * dt
        lim = self._abl_lim
        x_new = np.array(
            (
                px + dt * vx + h * cn,
                py + dt * vy + h * ce,
                pz + dt * vz + h * cd,
                vx + dt * cn,
                vy + dt * ce,
                vz + dt * cd,
                -lim if bx < -lim else (lim if bx > lim else bx),
                -lim if by < -lim else (lim if by > lim else by),
                -lim if bz < -lim else (lim if bz > lim else bz),
                ofs,
            )
        )
        P_new = np.dot(np.dot(F, P), F.T)
        if dt != self._q_dt_s:
            self._q_dt_s = dt
            self._q_dt = np.diag(self._q_c * dt)
        P_new += self._q_dt
        if max(P_new.diagonal().tolist()) > P_MAX:
            # LPE: a variance that has run away stops propagating (with its correlations).
            runaway = np.flatnonzero(P_new.diagonal() > P_MAX)
            P_new[runaway, :] = P[runaway, :]
            P_new[:, runaway] = P[:, runaway]
        return x_new, P_new

    def _update_process_noise(self) -> None:
        p = self.params
        vxy = p.lpe_pn_v**2 + p.lpe_acc_xy**2
        vz = p.lpe_pn_vz**2 + p.lpe_acc_z**2
        # The offset is only a state while both height sensors are in use.
        if self._hgt_ref == HGT_REF_GPS:
            ofs = p.lpe_pn_baro**2 if self._map is not None else 0.0
        else:
            ofs = p.lpe_pn_gps_z**2 if self._map is not None and self._baro_initialised else 0.0
        self._q_c = np.array([p.lpe_pn_p**2] * 3 + [vxy, vxy, vz] + [p.lpe_pn_b**2] * 3 + [ofs])
        self._q_dt_s = math.nan

    # ------------------------------------------------------------------ barometer

    def fuse_baro(self, alt_amsl_m: float) -> bool:
        """Fuse a barometric altitude [m AMSL] at the current filter time; True when it changed the
        estimate. PX4's baro delay is 0: call this after the prediction nearest the baro sample.

        The first sample defines the altitude reference while GPS does not (see the module doc).
        """
        t_now = self._t_us
        if t_now is None or not math.isfinite(alt_amsl_m) or not ALT_MIN_M < alt_amsl_m < ALT_MAX_M:
            return False
        if not self._baro_initialised:
            self._init_baro(alt_amsl_m, t_now)
            self._last_baro_fused_us = t_now
            return True
        x, P, ratio = self._baro_update(self.x, self.P, alt_amsl_m)
        self.baro_test_ratio = ratio
        if ratio <= 1.0:
            self.x, self.P = x, P
            self._last_baro_fused_us = t_now
            step = _Step(t_now, x, P)
            step.baro_alt = alt_amsl_m
            self._hist.append(step)
            return True
        if t_now - self._last_baro_fused_us > FUSION_RESET_TIMEOUT_US:
            if self._hgt_ref == HGT_REF_GPS:
                self._reset_to_baro(alt_amsl_m, t_now)
            else:
                self._reset_z_to_baro_reference(alt_amsl_m, t_now)
            self._last_baro_fused_us = t_now
            return True
        return False

    def _baro_update(self, x: np.ndarray, P: np.ndarray, alt: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Gated scalar update with h(x) = ref_alt − z (+ offset with the GPS reference); returns
        (x, P, test ratio)."""
        p = self.params
        if self._hgt_ref == HGT_REF_GPS:
            innov = alt - (self._ref_alt - x[X_Z] + x[X_HGT_OFS])
            pht = P[:, X_HGT_OFS] - P[:, X_Z]
            s = pht[X_HGT_OFS] - pht[X_Z] + p.lpe_bar_z**2
        else:
            innov = alt - (self._ref_alt - x[X_Z])
            pht = -P[:, X_Z]
            s = -pht[X_Z] + p.lpe_bar_z**2
        ratio = innov * innov / (p.ekf2_baro_gate**2 * s)
        if ratio > 1.0:
            return x, P, ratio
        k = pht / s
        x = x + k * innov
        P = P - k[:, None] * pht
        return x, 0.5 * (P + P.T), ratio

    def _init_baro(self, alt: float, t_now: int) -> None:
        x = self.x.copy()
        P = self.P.copy()
        r = self.params.lpe_bar_z**2
        if not self._z_initialised:
            self._ref_alt = alt
            x[X_Z] = 0.0
            x[X_HGT_OFS] = 0.0
            P[X_Z, :] = P[:, X_Z] = 0.0
            P[X_HGT_OFS, :] = P[:, X_HGT_OFS] = 0.0
            P[X_Z, X_Z] = r
            self._z_initialised = True
        elif self._hgt_ref == HGT_REF_GPS:
            # z is GPS-referenced already: the baro only brings its own offset.
            x[X_HGT_OFS] = alt - (self._ref_alt - x[X_Z])
            P[X_HGT_OFS, :] = 0.0
            P[:, X_HGT_OFS] = 0.0
            P[X_HGT_OFS, X_HGT_OFS] = P[X_Z, X_Z] + r
        else:
            # GPS defined z until now: the baro takes over with z continuous, and the GPS frame
            # becomes the offset. In the new frame z is off by this sample's noise only; the offset
            # carries z's former error (e_ofs = −e_z − n_baro).
            ref_baro = alt + x[X_Z]
            x[X_HGT_OFS] = self._ref_alt - ref_baro
            pz = P[X_Z, :].copy()
            P[X_HGT_OFS, :] = -pz
            P[:, X_HGT_OFS] = -pz
            P[X_Z, :] = P[:, X_Z] = 0.0
            P[X_Z, X_Z] = r
            P[X_Z, X_HGT_OFS] = P[X_HGT_OFS, X_Z] = r
            P[X_HGT_OFS, X_HGT_OFS] = pz[X_Z] + r
        self._baro_initialised = True
        self.x, self.P = x, P
        self._update_process_noise()
        self._restart_history(t_now)

    def _reset_to_baro(self, alt: float, t_now: int) -> None:
        """GPS reference, baro rejected for too long: if GPS height is being fused the baro offset
        has changed, otherwise the height estimate is wrong and is reset to the baro."""
        x = self.x.copy()
        P = self.P.copy()
        r = self.params.lpe_bar_z**2
        gps_height_recent = self._map is not None and t_now - self._last_fused_us[_G_VPOS] < FUSION_RESET_TIMEOUT_US
        if gps_height_recent:
            x[X_HGT_OFS] = alt - (self._ref_alt - x[X_Z])
            P[X_HGT_OFS, :] = P[:, X_HGT_OFS] = 0.0
            P[X_HGT_OFS, X_HGT_OFS] = P[X_Z, X_Z] + r
        else:
            z_new = self._ref_alt + x[X_HGT_OFS] - alt
            self.delta_z = float(z_new - x[X_Z])
            self.z_reset_counter += 1
            if self._map is not None:
                self._count_alt_reset(-self.delta_z)
            x[X_Z] = z_new
            P[X_Z, :] = P[:, X_Z] = 0.0
            P[X_Z, X_Z] = r + P[X_HGT_OFS, X_HGT_OFS]
        self.x, self.P = x, P
        self._restart_history(t_now)

    def _reset_z_to_baro_reference(self, alt: float, t_now: int) -> None:
        """Baro reference, baro rejected for too long: z is reset to the baro. The GPS offset moves
        with it, so the GPS altitude prediction ``z − offset`` and the global altitude do not jump."""
        x = self.x.copy()
        P = self.P.copy()
        r = self.params.lpe_bar_z**2
        z_new = self._ref_alt - alt
        dz = z_new - x[X_Z]
        pz = P[X_Z, :].copy()
        if self._map is not None:
            # offset' = offset + (z' − z): e_ofs' = e_ofs − e_z + e_z', with e_z' the sample noise.
            var_ofs = P[X_HGT_OFS, X_HGT_OFS] - 2.0 * pz[X_HGT_OFS] + pz[X_Z] + r
            row_ofs = P[X_HGT_OFS, :] - pz
            x[X_HGT_OFS] += dz
            P[X_HGT_OFS, :] = row_ofs
            P[:, X_HGT_OFS] = row_ofs
            P[X_Z, :] = P[:, X_Z] = 0.0
            P[X_Z, X_HGT_OFS] = P[X_HGT_OFS, X_Z] = r
            P[X_HGT_OFS, X_HGT_OFS] = var_ofs
        else:
            P[X_Z, :] = P[:, X_Z] = 0.0
        P[X_Z, X_Z] = r
        x[X_Z] = z_new
        self.delta_z = float(dz)
        self.z_reset_counter += 1
        self.x, self.P = x, P
        self._restart_history(t_now)

    # ------------------------------------------------------------------ GPS

    def fuse_gps(self, gps: GpsMeasurement) -> bool:
        """Fuse a GPS fix at its measurement time; True when it changed the estimate (fused, reset
        or set the origin).

        Fixes before the origin is set only count toward the initialisation checks. A fix older
        than the 0.5 s history, not newer than the previous one, without a 3-D fix, or with a
        non-finite or implausible position is dropped.
        """
        t_now = self._t_us
        if t_now is None:
            return False
        lat, lon, alt = gps.latitude_deg, gps.longitude_deg, gps.altitude_msl_m
        if not (math.isfinite(lat) and math.isfinite(lon) and math.isfinite(alt)):
            return False
        if abs(lat) > 90.0 or abs(lon) > 180.0 or not ALT_MIN_M < alt < ALT_MAX_M:
            return False
        if gps.fix_type < GPS_FIX_3D:
            self._gps_init_count = 0
            return False
        vel = (gps.vel_n_m_s, gps.vel_e_m_s, gps.vel_d_m_s)
        vel_ok = bool(gps.vel_ned_valid) and all(math.isfinite(v) for v in vel)
        # A receiver reached through MAVLink's GPS_RAW_INT gives ground speed and course, no vertical velocity.
        hvel_ok = not gps.vel_ned_valid and math.isfinite(vel[0]) and math.isfinite(vel[1])

        t_meas = min(gps.timestamp_sample - round(self.params.lpe_gps_delay * 1e6), t_now)
        if self._last_gps_meas_us is not None and t_meas <= self._last_gps_meas_us:
            return False
        hist = self._hist
        if t_meas < hist[0].t_us:
            return False

        p = self.params
        eph = gps.eph if math.isfinite(gps.eph) else 0.0
        epv = gps.epv if math.isfinite(gps.epv) else 0.0
        if self._map is None:
            init_ok = (
                (vel_ok or not gps.vel_ned_valid)  # a receiver that gives no NED velocity (MAVLink's GPS_RAW_INT)
                and gps.satellites_used >= GPS_INIT_MIN_SATS
                and math.isfinite(gps.eph)
                and math.isfinite(gps.epv)
                and gps.eph <= p.lpe_eph_max
                and gps.epv <= p.lpe_epv_max
            )
            self._gps_init_count = self._gps_init_count + 1 if init_ok else 0
            if self._gps_init_count < GPS_INIT_COUNT:
                return False

        var = np.array(
            [max(p.lpe_gps_xy, eph) ** 2] * 2
            + [max(p.lpe_gps_z, epv) ** 2]
            + [p.lpe_gps_vxy**2] * 2
            + [p.lpe_gps_vz**2]
        )
        k = bisect.bisect_right(hist, t_meas, key=_step_time) - 1
        base = hist[k]
        x_before = self.x

        if self._map is None:
            x, P = self._set_origin(base.x, base.P, lat, lon, alt, vel if vel_ok else None, var, t_meas)
            resets = (True, False, True, True)
        else:
            north, east = self._map.project(lat, lon)
            y = np.array(
                (north, east, self._ref_alt - alt, *vel)
                if vel_ok
                else (north, east, self._ref_alt - alt, *vel[:2])
                if hvel_ok
                else (north, east, self._ref_alt - alt)
            )
            x, P, resets = self._gps_update(base.x, base.P, y, var, t_meas)
            if x is base.x:
                return False

        self._last_gps_meas_us = t_meas
        base.x, base.P = x, P
        self._replay(k + 1)
        self._record_resets(x_before, resets)
        return True

    def _set_origin(
        self,
        x: np.ndarray,
        P: np.ndarray,
        lat: float,
        lon: float,
        alt: float,
        vel: Vec3 | None,
        var: np.ndarray,
        t_meas: int,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Place the origin at this fix, reset xy and velocity (when the fix has one) to it, and tie GPS
        altitude to z."""
        x = x.copy()
        P = P.copy()
        self._map = MapProjection(lat, lon)
        self._ref_timestamp = t_meas
        for i in (X_X, X_Y) if vel is None else (X_X, X_Y, X_VX, X_VY, X_VZ):
            P[i, :] = P[:, i] = 0.0
        x[X_X] = x[X_Y] = 0.0
        P[X_X, X_X] = P[X_Y, X_Y] = var[0]
        if vel is not None:
            x[X_VX], x[X_VY], x[X_VZ] = vel
            P[X_VX, X_VX] = P[X_VY, X_VY] = var[3]
            P[X_VZ, X_VZ] = var[5]
        if not self._baro_initialised:
            # No baro yet: GPS defines z (for good with the GPS reference, until the first baro
            # sample with the baro reference).
            self._ref_alt = alt
            x[X_Z] = 0.0
            P[X_Z, :] = P[:, X_Z] = 0.0
            P[X_Z, X_Z] = var[2]
            self._z_initialised = True
        elif self._hgt_ref == HGT_REF_GPS:
            # z stays continuous and the baro prediction ref − z + offset unchanged. The error of
            # this GPS altitude goes to the offset: the reference altitude defines the local frame,
            # so z keeps its baro-relative accuracy (and z_valid does not drop at the origin).
            new_ref = alt + x[X_Z]
            x[X_HGT_OFS] += self._ref_alt - new_ref
            P[X_HGT_OFS, X_HGT_OFS] += var[2]
            self._ref_alt = float(new_ref)
        else:
            self._init_gps_offset(x, P, alt, var[2])
        for g in range(4):
            self._last_fused_us[g] = t_meas
        self._update_process_noise()
        return x, P

    def _init_gps_offset(self, x: np.ndarray, P: np.ndarray, alt: float, var: float) -> None:
        """Baro reference: set the GPS altitude offset from one GPS altitude, in place. Its error is
        this sample's noise plus z's error (e_ofs = n_gps + e_z), hence z's row in P."""
        x[X_HGT_OFS] = alt - (self._ref_alt - x[X_Z])
        P[X_HGT_OFS, :] = P[X_Z, :]
        P[:, X_HGT_OFS] = P[:, X_Z]
        P[X_HGT_OFS, X_HGT_OFS] = P[X_Z, X_Z] + var

    def _gps_update(
        self, x: np.ndarray, P: np.ndarray, y: np.ndarray, var: np.ndarray, t_meas: int
    ) -> tuple[np.ndarray, np.ndarray, tuple[bool, ...]]:
        """Gate each group, fuse the accepted ones jointly, reset groups rejected for too long.

        The measurement rows are the states x, y, z, vx, vy, vz, except the altitude row with the
        baro reference, which measures z − offset. Returns the inputs themselves when nothing was
        fused or reset.
        """
        p = self.params
        n = len(y)
        alt_offset = self._gps_alt_has_offset()
        innov = y - x[:n]
        s_diag = P.diagonal()[:n] + var[:n]
        if alt_offset:
            innov[_ROW_ALT] += x[X_HGT_OFS]
            s_diag[_ROW_ALT] += P[X_HGT_OFS, X_HGT_OFS] - 2.0 * P[X_Z, X_HGT_OFS]
        norm_sq = innov * innov / s_diag
        accepted: list[int] = []
        to_reset = [False, False, False, False]
        ratios = [0.0, 0.0, 0.0, 0.0]
        for g, (rows, gate_name) in enumerate(_GPS_GROUPS):
            if rows[0] >= n:
                continue
            ratio = max(norm_sq[i] for i in rows) / getattr(p, gate_name) ** 2
            ratios[g] = float(ratio)
            if ratio <= 1.0:
                accepted.extend(rows)
                self._last_fused_us[g] = t_meas
            elif t_meas - self._last_fused_us[g] > FUSION_RESET_TIMEOUT_US:
                to_reset[g] = True
        self.gps_pos_test_ratio = max(ratios[_G_HPOS], ratios[_G_VPOS])
        self.gps_vel_test_ratio = max(ratios[_G_HVEL], ratios[_G_VVEL])

        if accepted:
            idx = np.array(accepted)
            pht = P[:, idx]  # P·Hᵀ
            col = accepted.index(_ROW_ALT) if alt_offset and _ROW_ALT in accepted else -1
            if col >= 0:
                pht[:, col] -= P[:, X_HGT_OFS]
            s = pht[idx, :]  # H·P·Hᵀ
            if col >= 0:
                s[col, :] -= pht[X_HGT_OFS, :]
            s += np.diag(var[idx])
            gain = np.linalg.solve(s, pht.T).T
            x = x + gain @ innov[idx]
            P = P - gain @ pht.T
            P = 0.5 * (P + P.T)
        if any(to_reset):
            x, P = self._reset_to_gps(x, P, y, var, to_reset, t_meas)
        return x, P, tuple(to_reset)

    def _reset_to_gps(
        self, x: np.ndarray, P: np.ndarray, y: np.ndarray, var: np.ndarray, groups: list[bool], t_meas: int
    ) -> tuple[np.ndarray, np.ndarray]:
        x = x.copy()
        P = P.copy()
        for g, (rows, _) in enumerate(_GPS_GROUPS):
            if not groups[g]:
                continue
            self._last_fused_us[g] = t_meas
            if g == _G_VPOS and self._gps_alt_has_offset():
                # Baro reference: the GPS altitude has moved against the baro, not the vehicle.
                self._init_gps_offset(x, P, self._ref_alt - y[_ROW_ALT], var[_ROW_ALT])
                continue
            for i in rows:
                if i == X_Z and self._baro_initialised:
                    # Keep the baro consistent with the new height (ref − z + offset unchanged).
                    x[X_HGT_OFS] += y[i] - x[X_Z]
                    P[X_HGT_OFS, :] = P[:, X_HGT_OFS] = 0.0
                P[i, :] = P[:, i] = 0.0
                x[i] = y[i]
                P[i, i] = var[i]
                if i == X_Z and self._baro_initialised:
                    P[X_HGT_OFS, X_HGT_OFS] = P[X_Z, X_HGT_OFS] = P[X_HGT_OFS, X_Z] = var[i]
        return x, P

    def _record_resets(self, x_before: np.ndarray, resets: tuple[bool, ...]) -> None:
        d = self.x - x_before
        if resets[_G_HPOS]:
            self.xy_reset_counter += 1
            self.delta_xy = (float(d[X_X]), float(d[X_Y]))
        if resets[_G_VPOS]:
            if self._gps_alt_has_offset():
                self._count_alt_reset(float(d[X_HGT_OFS]))
            else:
                self.z_reset_counter += 1
                self.delta_z = float(d[X_Z])
                self._count_alt_reset(-self.delta_z)
        if resets[_G_HVEL]:
            self.vxy_reset_counter += 1
            self.delta_vxy = (float(d[X_VX]), float(d[X_VY]))
        if resets[_G_VVEL]:
            self.vz_reset_counter += 1
            self.delta_vz = float(d[X_VZ])

    def _count_alt_reset(self, delta_alt: float) -> None:
        self.alt_reset_counter += 1
        self.delta_alt = delta_alt

    # ------------------------------------------------------------------ land detector

    def fuse_land(self) -> bool:
        """Fuse the land detector's "landed" at the current filter time (the module fuses it only while the
        detector also finds the vehicle at rest, as EKF2 fuses zero velocity: a plane is still "landed" in its
        takeoff roll): the vehicle stands still, so
        its horizontal velocity is zero with σ ``LPE_LAND_VXY`` (LPE's land measurement, fused by
        default, ``LPE_FUSION`` bit 4; its height-above-ground row needs a terrain state this filter
        does not have). Without it a vehicle waiting on the ground follows the GPS velocity noise
        and its position wanders by decimetres. True when fused (after the origin is set)."""
        if self._t_us is None or self._map is None:
            return False
        var = self.params.lpe_land_vxy**2
        self._fuse_velocity((0.0, 0.0, var, var))
        return True

    def fuse_airspeed(
        self, true_airspeed: float, q: Quat, wind_ne: tuple[float, float], wind_var_ne: tuple[float, float]
    ) -> bool:
        """Fuse, while GPS is lost, the horizontal velocity that the true airspeed [m/s] along the body x axis
        (attitude ``q``, body → NED) and the wind estimate [m/s] with its variances give: EKF2's airspeed
        dead reckoning, on this filter's velocity states. True when fused: the origin is set, no horizontal
        GPS aiding for ``GPS_TIMEOUT_US``, ``LPE_AIRSPD_VXY`` positive, every input finite and plausible, and the
        innovation within ``EKF2_TAS_GATE``."""
        t_now = self._t_us
        sigma = self.params.lpe_airspd_vxy
        if t_now is None or self._map is None or sigma <= 0.0 or not self._gps_lost(t_now):
            return False
        numbers = (true_airspeed, *q, *wind_ne, *wind_var_ne)
        if not all(math.isfinite(v) for v in numbers) or not 0.0 <= true_airspeed < AIRSPEED_MAX:
            return False
        if min(wind_var_ne) < 0.0 or quat.norm(q) < 0.5:
            return False
        heading = quat.rotate(quat.normalized(q), (1.0, 0.0, 0.0))
        measured = (
            true_airspeed * heading[0] + wind_ne[0],
            true_airspeed * heading[1] + wind_ne[1],
            wind_var_ne[0] + sigma * sigma,
            wind_var_ne[1] + sigma * sigma,
        )
        innovation = np.array(measured[:2]) - self.x[_HVEL_ROWS]
        s = self.P[_HVEL_ROWS, _HVEL_ROWS] + np.array(measured[2:])
        if np.any(innovation * innovation > self.params.ekf2_tas_gate**2 * s):
            return False
        self._fuse_velocity(measured)
        return True

    def _gps_lost(self, t_now: int) -> bool:
        return t_now - max(self._last_fused_us[_G_HPOS], self._last_fused_us[_G_HVEL]) > GPS_TIMEOUT_US

    def _fuse_velocity(self, measured: tuple[float, float, float, float]) -> None:
        """Fuse a horizontal velocity (north, east, their variances) at the current filter time, kept in the
        history so that a later, delayed GPS fusion replays it."""
        self.x, self.P = self._velocity_update(self.x, self.P, measured)
        step = _Step(self._t_us or 0, self.x, self.P)
        step.velocity = measured
        self._hist.append(step)

    @staticmethod
    def _velocity_update(
        x: np.ndarray, P: np.ndarray, measured: tuple[float, float, float, float]
    ) -> tuple[np.ndarray, np.ndarray]:
        pht = P[:, _HVEL_ROWS]
        s = pht[_HVEL_ROWS, :] + np.diag(measured[2:])
        gain = np.linalg.solve(s, pht.T).T
        x = x + gain @ (np.array(measured[:2]) - x[_HVEL_ROWS])
        P = P - gain @ pht.T
        return x, 0.5 * (P + P.T)

    # ------------------------------------------------------------------ history

    def _replay(self, start: int) -> None:
        """Re-run the predictions and baro fusions recorded after index ``start − 1``."""
        hist = self._hist
        x, P = hist[start - 1].x, hist[start - 1].P
        for i in range(start, len(hist)):
            step = hist[i]
            if step.prediction is not None:
                x, P = self._propagate(x, P, step.prediction)
            elif step.baro_alt is not None:
                x, P, _ = self._baro_update(x, P, step.baro_alt)
            elif step.velocity is not None:
                x, P = self._velocity_update(x, P, step.velocity)
            step.x, step.P = x, P
        self.x, self.P = x, P

    def _restart_history(self, t_now: int) -> None:
        """After a reset made at the current time, older steps no longer describe the same frame."""
        self._hist.clear()
        self._hist.append(_Step(t_now, self.x, self.P))

    # ------------------------------------------------------------------ output

    def estimate(self) -> LocalPositionEstimate:
        """Snapshot of the current estimate with validity flags and accuracies."""
        p = self.params
        px, py, pz, vx, vy, vz, bx, by, bz, ofs = self.x.tolist()
        d = self.P.diagonal().tolist()
        eph = math.sqrt(d[X_X] + d[X_Y])
        epv = math.sqrt(d[X_Z])
        evh = math.sqrt(d[X_VX] + d[X_VY])
        evv = math.sqrt(d[X_VZ])
        origin = self._map is not None
        t_now = self._t_us or 0
        xy_valid = origin and eph <= p.lpe_xy_pub
        v_xy_valid = origin and max(d[X_VX], d[X_VY]) <= p.lpe_vxy_pub**2
        z_valid = self._z_initialised and epv <= p.lpe_z_pub
        if self._hgt_ref == HGT_REF_GPS:
            ref_alt, baro_offset = self._ref_alt, ofs
        else:
            ref_alt, baro_offset = self._ref_alt + ofs, -ofs
        if self._map is not None:
            lat, lon = self._map.reproject(px, py)
            ref_lat, ref_lon = self._map.lat0_deg, self._map.lon0_deg
            alt = ref_alt - pz
        else:
            lat = lon = alt = ref_lat = ref_lon = math.nan
        return LocalPositionEstimate(
            timestamp_sample=t_now,
            position=(px, py, pz),
            velocity=(vx, vy, vz),
            acceleration=self._accel_ned,
            xy_valid=xy_valid,
            z_valid=z_valid,
            v_xy_valid=v_xy_valid,
            v_z_valid=z_valid,
            eph=eph,
            epv=epv,
            evh=evh,
            evv=evv,
            dead_reckoning=origin and self._gps_lost(t_now),
            xy_global=origin,
            z_global=origin,
            ref_timestamp=self._ref_timestamp,
            ref_lat=ref_lat,
            ref_lon=ref_lon,
            ref_alt=ref_alt,
            lat=lat,
            lon=lon,
            alt=alt,
            delta_xy=self.delta_xy,
            xy_reset_counter=self.xy_reset_counter,
            delta_z=self.delta_z,
            z_reset_counter=self.z_reset_counter,
            delta_vxy=self.delta_vxy,
            vxy_reset_counter=self.vxy_reset_counter,
            delta_vz=self.delta_vz,
            vz_reset_counter=self.vz_reset_counter,
            delta_alt=self.delta_alt,
            alt_reset_counter=self.alt_reset_counter,
            accel_bias=(bx, by, bz),
            baro_offset=baro_offset,
        )
