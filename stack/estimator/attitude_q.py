"""Quaternion complementary filter for attitude (PX4 ``attitude_estimator_q``).

Follows ``src/modules/attitude_estimator_q/attitude_estimator_q_main.cpp``: the gyro propagates the
attitude, the accelerometer pulls the predicted down axis toward the measured gravity direction, the
magnetometer pulls the heading toward magnetic north (plus declination), and the integral of both
corrections estimates the gyro bias while the vehicle rotates slowly.

Sign convention of the bias: PX4 stores the negated bias and adds it to the gyro. Here
``gyro_bias`` is the physical additive bias (``measured = true + gyro_bias``), so consumers such as
:class:`stack.estimator.angular_velocity.AngularVelocityFilter` subtract it.
"""

from __future__ import annotations

import math

from stack.mathlib import quaternion as quat
from stack.mathlib import vector as vec
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G, constrain, wrap_pi
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet

DT_MIN_S = 1e-5
DT_MAX_S = 0.02
SPIN_RATE_BIAS_LIMIT = 0.175  # rad/s: above this the bias is not learned (10 deg/s)
SPIN_RATE_MAG_BOOST = 0.873  # rad/s: above this (50 deg/s) the mag gain grows with the spin rate
MAG_GAIN_BOOST_MAX = 10.0
ACCEL_NORM_MIN_SQ = (0.9 * CONSTANTS_ONE_G) ** 2
ACCEL_NORM_MAX_SQ = (1.1 * CONSTANTS_ONE_G) ** 2
DEGENERATE_NORM = 1e-2  # accel [m/s²] or horizontal mag [G] too small to give a direction
ALIGN_TIME_S = 2.0
"""Accelerometer and magnetometer samples are averaged this long before the first attitude is set."""
ALIGN_SPIN_RATE_MAX = 0.1  # rad/s: a vehicle turning faster than this restarts the alignment
ALIGN_MAG_SAMPLES_MIN = 10


class AttitudeEstimatorParams(ParamSet):
    """The filter's weights, gyro bias limit, magnetic declination and acceleration compensation (the catalogue's
    ATT_*); :meth:`AttitudeEstimatorQ.set_params` clamps them to PX4's ranges."""

    att_w_acc: float
    att_w_mag: float
    att_w_gyro_bias: float
    att_bias_max: float
    att_mag_decl: float
    att_acc_comp: int


class AttitudeEstimatorQ:
    """Attitude (body FRD → NED quaternion) and gyro bias from gyro, accelerometer and magnetometer.

    Parameters (PX4 names, defaults, ranges):

    - ``ATT_W_ACC`` 0.2 [0, 1]: accelerometer (tilt) correction weight, 1/s.
    - ``ATT_W_MAG`` 0.1 [0, 1]: magnetometer (heading) correction weight, 1/s; 0 ignores the mag.
    - ``ATT_W_GYRO_BIAS`` 0.1 [0, 1]: gyro bias learning weight, 1/s.
    - ``ATT_BIAS_MAX`` 0.05 [0, 2] rad/s: limit of each gyro bias component.
    - ``ATT_MAG_DECL`` 0 [-180, 180] deg: magnetic declination (east positive).
    - ``ATT_ACC_COMP`` 0 {0, 1}: subtract the caller's kinematic acceleration from the accelerometer
      and drop the 0.9–1.1 g gate.

    Outputs: ``q`` (body FRD → NED), ``gyro_bias`` (additive, rad/s), ``rates`` (gyro minus bias of
    the last step, rad/s) and ``initialised``.

    Alignment: PX4's attitude_estimator_q takes its first attitude from a single accelerometer and
    magnetometer sample, which puts one sample's noise into the heading (5° RMS for a 0.02 G mag noise
    in a 0.22 G horizontal field) for the ~10 s the 0.1/s mag weight needs to remove it. Here, as EKF2
    does before its tilt and heading alignment (``Ekf::initialiseFilter``, low-pass filtered samples),
    the samples are averaged first: ALIGN_TIME_S of a still vehicle (spin below ALIGN_SPIN_RATE_MAX,
    specific force within 0.9–1.1 g), with at least ALIGN_MAG_SAMPLES_MIN magnetometer samples when the
    magnetometer is used; any motion restarts the average.
    """

    __slots__ = (
        "_align_accel",
        "_align_mag",
        "_align_mag_count",
        "_align_time",
        "_mag",
        "_mag_decl",
        "_w_acc",
        "_w_bias",
        "_w_mag",
        "acc_comp",
        "bias_max",
        "gyro_bias",
        "initialised",
        "q",
        "rates",
    )

    def __init__(self, params: AttitudeEstimatorParams | None = None) -> None:
        self.q: Quat = quat.IDENTITY
        self.gyro_bias: Vec3 = vec.ZERO3
        self.rates: Vec3 = vec.ZERO3
        self.initialised = False
        self._mag: Vec3 | None = None
        self._mag_decl = 0.0
        self._restart_alignment()
        self.set_params(params or AttitudeEstimatorParams())

    def set_params(self, params: AttitudeEstimatorParams) -> None:
        """Apply the parameters, clamped to their PX4 ranges.

        A declination change rotates the current estimate at once, as PX4 does, so the heading
        loop does not wind the gyro bias up while it catches up.
        """
        self._w_acc = constrain(params.att_w_acc, 0.0, 1.0)
        self._w_mag = constrain(params.att_w_mag, 0.0, 1.0)
        self._w_bias = constrain(params.att_w_gyro_bias, 0.0, 1.0)
        self.acc_comp = bool(params.att_acc_comp)
        lim = self.bias_max = constrain(params.att_bias_max, 0.0, 2.0)
        b = self.gyro_bias
        self.gyro_bias = (constrain(b[0], -lim, lim), constrain(b[1], -lim, lim), constrain(b[2], -lim, lim))
        decl = math.radians(constrain(params.att_mag_decl, -180.0, 180.0))
        if self.initialised and abs(decl - self._mag_decl) > 1e-4:
            turn = quat.from_axis_angle((0.0, 0.0, 1.0), decl - self._mag_decl)
            self.q = quat.normalized(quat.mul(turn, self.q))
        self._mag_decl = decl

    def reset(self, q: Quat | None = None) -> None:
        """Forget the estimate. With ``q`` the filter restarts from that attitude; without it, it
        re-initialises from the next accelerometer (and magnetometer) sample."""
        self.gyro_bias = vec.ZERO3
        self.rates = vec.ZERO3
        if q is not None and quat.is_finite(q) and quat.norm(q) > 0.5:
            self.q = quat.normalized(q)
            self.initialised = True
        else:
            self.q = quat.IDENTITY
            self.initialised = False
            self._restart_alignment()

    def _restart_alignment(self) -> None:
        self._align_accel: Vec3 = vec.ZERO3
        self._align_mag: Vec3 = vec.ZERO3
        self._align_mag_count = 0
        self._align_time = 0.0

    def update(
        self,
        dt: float,
        gyro: Vec3,
        accel: Vec3,
        mag: Vec3 | None = None,
        accel_compensation: Vec3 | None = None,
    ) -> bool:
        """Run one filter step; return True when ``q`` holds a valid, updated attitude.

        Args:
            dt: time since the previous IMU sample [s], clamped to [1e-5, 0.02] as PX4 does.
            gyro: measured body rates [rad/s], FRD.
            accel: measured specific force [m/s²], FRD (reads (0, 0, -g) at rest, level).
            mag: a new magnetometer sample [G], FRD, or None. The latest sample keeps being used
                on the IMU steps in between, as in PX4 where the mag is slower than the IMU.
            accel_compensation: kinematic acceleration of the vehicle in NED [m/s²] (for example
                the derivative of the GPS velocity); used only with ATT_ACC_COMP = 1.
        """
        spin_rate = vec.norm(gyro)
        accel_norm_sq = vec.dot(accel, accel)
        # Norms catch both non-finite components and magnitudes that overflow the arithmetic.
        if not (math.isfinite(spin_rate) and math.isfinite(accel_norm_sq) and math.isfinite(dt)):
            return False
        new_mag = mag is not None and DEGENERATE_NORM < vec.norm(mag) < math.inf
        if new_mag:
            self._mag = mag
        if accel_norm_sq < DEGENERATE_NORM * DEGENERATE_NORM:
            return False
        dt = constrain(dt, DT_MIN_S, DT_MAX_S)
        if not self.initialised:
            return self._align(dt, spin_rate, accel, accel_norm_sq, mag if new_mag else None)

        q = self.q
        corr = vec.ZERO3

        if self._w_mag > 0.0 and self._mag is not None:
            mag_earth = quat.rotate(q, self._mag)
            mag_err = wrap_pi(math.atan2(mag_earth[1], mag_earth[0]) - self._mag_decl)
            gain = self._w_mag
            if spin_rate > SPIN_RATE_MAG_BOOST:
                gain *= min(spin_rate / SPIN_RATE_MAG_BOOST, MAG_GAIN_BOOST_MAX)
            # Yaw the estimate about the world down axis against the heading error.
            corr = vec.scale(quat.rotate_inv(q, (0.0, 0.0, -mag_err)), gain)

        if self.acc_comp or ACCEL_NORM_MIN_SQ < accel_norm_sq < ACCEL_NORM_MAX_SQ:
            gravity_dir = accel
            if self.acc_comp and accel_compensation is not None and vec.is_finite(accel_compensation):
                gravity_dir = vec.sub(accel, quat.rotate_inv(q, accel_compensation))
            w, x, y, z = q
            down_in_body = (2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z)
            # The measured specific force points up (−down); k × f̂ turns the predicted down axis
            # toward the measured one.
            corr = vec.add(corr, vec.scale(vec.cross(down_in_body, vec.normalized(gravity_dir)), self._w_acc))

        bias = self.gyro_bias
        if spin_rate < SPIN_RATE_BIAS_LIMIT:
            k = self._w_bias * dt
            lim = self.bias_max
            bias = (
                constrain(bias[0] - corr[0] * k, -lim, lim),
                constrain(bias[1] - corr[1] * k, -lim, lim),
                constrain(bias[2] - corr[2] * k, -lim, lim),
            )

        rates = vec.sub(gyro, bias)
        q_new = quat.integrate(q, vec.add(rates, corr), dt)
        if not quat.is_finite(q_new):
            self.gyro_bias = vec.ZERO3
            self.rates = vec.ZERO3
            return False
        self.q = q_new
        self.gyro_bias = bias
        self.rates = rates
        return True

    def _align(self, dt: float, spin_rate: float, accel: Vec3, accel_norm_sq: float, mag: Vec3 | None) -> bool:
        """Average a still vehicle's samples; set the first attitude from them once there are enough."""
        if spin_rate > ALIGN_SPIN_RATE_MAX or not ACCEL_NORM_MIN_SQ < accel_norm_sq < ACCEL_NORM_MAX_SQ:
            self._restart_alignment()
            return False
        self._align_accel = vec.add(self._align_accel, accel)
        self._align_time += dt
        if mag is not None:
            self._align_mag = vec.add(self._align_mag, mag)
            self._align_mag_count += 1
        use_mag = self._w_mag > 0.0
        if self._align_time < ALIGN_TIME_S or (use_mag and self._align_mag_count < ALIGN_MAG_SAMPLES_MIN):
            return False
        mean_mag = vec.scale(self._align_mag, 1.0 / self._align_mag_count) if self._align_mag_count else None
        # The accelerometer sum's direction is its mean's; only the direction is used.
        aligned = self._init_from_vectors(self._align_accel, mean_mag if use_mag else None)
        if not aligned:
            self._restart_alignment()
        return aligned

    def _init_from_vectors(self, accel: Vec3, mag: Vec3 | None) -> bool:
        """Attitude from gravity and magnetic north: rows of the body→NED matrix are N, E, D in body.

        Without a magnetometer (``mag`` None) the body x axis projected on the horizontal plane is taken
        as north, i.e. the filter starts at yaw 0.
        """
        down = vec.normalized(vec.neg(accel))
        ref = mag if mag is not None else (1.0, 0.0, 0.0)
        north = vec.sub(ref, vec.scale(down, vec.dot(ref, down)))
        if vec.norm(north) < DEGENERATE_NORM:
            return False
        north = vec.normalized(north)
        east = vec.cross(down, north)
        q = quat.from_dcm((north, east, down))
        if mag is not None:
            q = quat.mul(quat.from_axis_angle((0.0, 0.0, 1.0), self._mag_decl), q)
        q = quat.normalized(q)
        if not quat.is_finite(q):
            return False
        self.q = q
        self.initialised = True
        return True
