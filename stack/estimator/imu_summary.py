"""The IMU between two ``vehicle_imu_status`` messages: means and extremes, as PX4's ``VehicleIMU`` reports them
every STATUS_INTERVAL_US (the attitude estimator module on the SIH's IMU, the pixhawk adapter on the Pixhawk's)."""

from __future__ import annotations

import math

from stack.msg.estimation import VehicleImuStatus
from stack.msg.sensors import SensorAccel, SensorGyro

STATUS_INTERVAL_US = 100_000
"""How often the IMU's and the estimator's status are published (10 Hz: the commander's checks need no more)."""


class ImuSummary:
    """Means and extremes of the IMU between two ``vehicle_imu_status`` messages."""

    def __init__(self) -> None:
        self.start_us = 0
        self._reset(0)

    def _reset(self, start_us: int) -> None:
        self.start_us = start_us
        self.n = 0
        self.gyro_sum = [0.0, 0.0, 0.0]
        self.accel_sum = [0.0, 0.0, 0.0]
        self.max_gyro = 0.0
        self.min_accel = math.inf
        self.accel_n = 0

    def add(self, t: int, gyro: tuple[float, float, float], accel: SensorAccel | None) -> None:
        if self.n == 0 and self.start_us == 0:
            self.start_us = t
        self.n += 1
        for i in range(3):
            self.gyro_sum[i] += gyro[i]
        self.max_gyro = max(self.max_gyro, math.sqrt(gyro[0] ** 2 + gyro[1] ** 2 + gyro[2] ** 2))
        if accel is not None:
            a = (accel.x, accel.y, accel.z)
            self.accel_n += 1
            for i in range(3):
                self.accel_sum[i] += a[i]
            self.min_accel = min(self.min_accel, math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2))

    def status(self, gyro_msg: SensorGyro) -> VehicleImuStatus:
        span = max(gyro_msg.timestamp_sample - self.start_us, 1) * 1e-6
        n, na = max(self.n, 1), max(self.accel_n, 1)
        status = VehicleImuStatus(
            timestamp_sample=gyro_msg.timestamp_sample,
            accel_device_id=gyro_msg.device_id,
            gyro_device_id=gyro_msg.device_id,
            gyro_error_count=gyro_msg.error_count,
            accel_rate_hz=self.accel_n / span,
            gyro_rate_hz=self.n / span,
            mean_accel=tuple(v / na for v in self.accel_sum),
            mean_gyro=tuple(v / n for v in self.gyro_sum),
            max_gyro_norm=self.max_gyro,
            min_accel_norm=self.min_accel if self.accel_n else 0.0,
            temperature_gyro=gyro_msg.temperature,
        )
        self._reset(gyro_msg.timestamp_sample)
        return status
