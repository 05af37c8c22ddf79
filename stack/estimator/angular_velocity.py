"""Gyro pipeline feeding the rate controller (PX4 ``sensors/vehicle_angular_velocity``).

Follows ``VehicleAngularVelocity.cpp`` for a non-FIFO gyro: each sample passes a 2nd-order
Butterworth low-pass (IMU_GYRO_CUTOFF); the angular acceleration is the finite difference of
successive *filtered* samples over the measured sample interval, smoothed by a first-order
low-pass (IMU_DGYRO_CUTOFF); the estimated bias is subtracted from the filtered rate at the output,
so a bias update neither rings through the filter nor spikes the derivative. The notch filters of
PX4 (all disabled by default) are not part of this pipeline.
"""

from __future__ import annotations

import math

from stack.mathlib.filters import AlphaFilter, LowPassFilter2p
from stack.mathlib.vector import ZERO3, Vec3
from stack.params.binding import ParamSet

DT_MIN_S = 2e-5
DT_MAX_S = 0.02
RATE_WINDOW_SAMPLES = 50  # intervals averaged before the sample rate is re-checked
RATE_TOLERANCE = 0.02  # relative change of the measured rate that triggers a filter re-design


class GyroFilterParams(ParamSet):
    """The rate and angular acceleration low-pass cutoffs (the catalogue's IMU_*)."""

    imu_gyro_cutoff: float
    imu_dgyro_cutoff: float


class AngularVelocityFilter:
    """Filtered, bias-corrected body rates and their filtered derivative from raw gyro samples.

    Parameters (PX4 names, defaults, ranges):

    - ``IMU_GYRO_CUTOFF`` 40 [0, 1000] Hz: rate low-pass cutoff; 0 (or ≥ Nyquist) disables it.
    - ``IMU_DGYRO_CUTOFF`` 20 [0, 1000] Hz: angular-acceleration low-pass cutoff; 0 disables it.

    ``sample_rate_hz`` is the nominal gyro rate used until the measured rate is known; the filters
    are re-designed when the mean interval of the last 50 samples differs from it by more than 2 %.
    """

    __slots__ = (
        "_dgyro_cutoff_hz",
        "_gyro_cutoff_hz",
        "_interval_count",
        "_interval_sum_s",
        "_lp_accel",
        "_lp_rate",
        "_rate_prev",
        "_timestamp_last_us",
        "sample_rate_hz",
        "xyz",
        "xyz_derivative",
    )

    def __init__(self, params: GyroFilterParams | None = None, sample_rate_hz: float = 250.0) -> None:
        params = params or GyroFilterParams()
        self._gyro_cutoff_hz = max(params.imu_gyro_cutoff, 0.0)
        self._dgyro_cutoff_hz = max(params.imu_dgyro_cutoff, 0.0)
        self.sample_rate_hz = sample_rate_hz
        self._lp_rate = [LowPassFilter2p(sample_rate_hz, self._gyro_cutoff_hz) for _ in range(3)]
        self._lp_accel = [AlphaFilter(sample_rate_hz, self._dgyro_cutoff_hz) for _ in range(3)]
        self._rate_prev: Vec3 = ZERO3
        self._timestamp_last_us: int | None = None
        self._interval_sum_s = 0.0
        self._interval_count = 0
        self.xyz: Vec3 = ZERO3
        self.xyz_derivative: Vec3 = ZERO3

    def set_params(self, params: GyroFilterParams) -> None:
        """Change the cutoffs; the filters restart from the current output."""
        self._gyro_cutoff_hz = max(params.imu_gyro_cutoff, 0.0)
        self._dgyro_cutoff_hz = max(params.imu_dgyro_cutoff, 0.0)
        self._design(self.sample_rate_hz)

    def reset(self) -> None:
        """Forget all history; the next sample re-initialises the filters."""
        self._timestamp_last_us = None
        self._interval_sum_s = 0.0
        self._interval_count = 0
        self.xyz = ZERO3
        self.xyz_derivative = ZERO3

    def update(self, timestamp_sample_us: int, gyro: Vec3, bias: Vec3 = ZERO3) -> tuple[Vec3, Vec3]:
        """Feed one raw gyro sample [rad/s, FRD]; return (xyz [rad/s], xyz_derivative [rad/s²]).

        ``bias`` is the additive gyro bias estimate (e.g. ``AttitudeEstimatorQ.gyro_bias``). A
        sample or bias with a non-finite component is ignored and the last output is returned.
        """
        gx, gy, gz = gyro
        if not (math.isfinite(gx) and math.isfinite(gy) and math.isfinite(gz)):
            return self.xyz, self.xyz_derivative
        bx, by, bz = bias
        if not (math.isfinite(bx) and math.isfinite(by) and math.isfinite(bz)):
            return self.xyz, self.xyz_derivative

        last = self._timestamp_last_us
        if last is None:
            self._timestamp_last_us = timestamp_sample_us
            lp_rate = self._lp_rate
            lp_accel = self._lp_accel
            self._rate_prev = (lp_rate[0].reset(gx), lp_rate[1].reset(gy), lp_rate[2].reset(gz))
            for f in lp_accel:
                f.reset(0.0)
            self.xyz = (gx - bx, gy - by, gz - bz)
            self.xyz_derivative = ZERO3
            return self.xyz, self.xyz_derivative

        if timestamp_sample_us <= last:
            # Repeated or reordered timestamp: assume one nominal interval, as PX4 does.
            dt = 1.0 / self.sample_rate_hz
        else:
            dt = (timestamp_sample_us - last) * 1e-6
            self._track_sample_rate(dt)
        self._timestamp_last_us = timestamp_sample_us
        dt = min(max(dt, DT_MIN_S), DT_MAX_S)
        inv_dt = 1.0 / dt

        lp_rate = self._lp_rate
        lp_accel = self._lp_accel
        fx = lp_rate[0].apply(gx)
        fy = lp_rate[1].apply(gy)
        fz = lp_rate[2].apply(gz)
        px, py, pz = self._rate_prev
        self._rate_prev = (fx, fy, fz)
        self.xyz_derivative = (
            lp_accel[0].update((fx - px) * inv_dt),
            lp_accel[1].update((fy - py) * inv_dt),
            lp_accel[2].update((fz - pz) * inv_dt),
        )
        self.xyz = (fx - bx, fy - by, fz - bz)
        return self.xyz, self.xyz_derivative

    def _track_sample_rate(self, dt: float) -> None:
        self._interval_sum_s += dt
        self._interval_count += 1
        if self._interval_count < RATE_WINDOW_SAMPLES:
            return
        measured_hz = self._interval_count / self._interval_sum_s
        self._interval_sum_s = 0.0
        self._interval_count = 0
        if abs(measured_hz - self.sample_rate_hz) > RATE_TOLERANCE * self.sample_rate_hz:
            self._design(measured_hz)

    def _design(self, sample_rate_hz: float) -> None:
        """(Re-)design all filters for ``sample_rate_hz`` and restart them from the current output."""
        self.sample_rate_hz = sample_rate_hz
        for axis in range(3):
            lp = self._lp_rate[axis]
            lp.set_cutoff(sample_rate_hz, self._gyro_cutoff_hz)
            lp.reset(self._rate_prev[axis])
            acc = self._lp_accel[axis]
            acc.set_cutoff(sample_rate_hz, self._dgyro_cutoff_hz)
            acc.reset(self.xyz_derivative[axis])
