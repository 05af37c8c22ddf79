"""Kinematic acceleration from velocity measurements, for attitude_estimator_q's ATT_ACC_COMP.

While the vehicle accelerates, the accelerometer's specific force is no longer gravity alone and a
complementary filter would pull its tilt toward the thrust direction. PX4's attitude_estimator_q
subtracts the acceleration obtained by differencing the position estimate's (or GPS) velocity. The
difference of noisy 10 Hz velocities is noisy, so it is low-passed here (ATT_ACC_COMP_LP).
"""

from __future__ import annotations

import math

from stack.mathlib.filters import AlphaFilter
from stack.mathlib.vector import Vec3

MAX_GAP_S = 0.5  # velocities further apart than this are not differenced


class VelocityDerivative:
    """NED acceleration [m/s²] from timestamped NED velocities [m/s], first-order low-passed."""

    __slots__ = ("_cutoff_hz", "_filters", "_time_us", "_velocity", "acceleration")

    def __init__(self, cutoff_hz: float = 1.0) -> None:
        self._cutoff_hz = cutoff_hz
        self._filters = [AlphaFilter() for _ in range(3)]
        self._velocity: Vec3 | None = None
        self._time_us = 0
        self.acceleration: Vec3 | None = None

    def reset(self) -> None:
        self._filters = [AlphaFilter() for _ in range(3)]
        self._velocity = None
        self.acceleration = None

    def update(self, time_us: int, velocity: Vec3) -> Vec3 | None:
        """Take one velocity sample; returns the filtered acceleration once two samples are in."""
        if not all(math.isfinite(v) for v in velocity):
            self.reset()
            return None
        previous, previous_time = self._velocity, self._time_us
        self._velocity, self._time_us = velocity, time_us
        if previous is None or time_us <= previous_time:
            return self.acceleration
        span = (time_us - previous_time) * 1e-6
        if span > MAX_GAP_S:
            self.reset()
            self._velocity, self._time_us = velocity, time_us
            return None
        for f in self._filters:
            f.set_time_constant(span, 1.0 / (2.0 * math.pi * self._cutoff_hz) if self._cutoff_hz > 0 else 0.0)
        self.acceleration = tuple(
            f.update((v - p) / span) for f, v, p in zip(self._filters, velocity, previous, strict=True)
        )
        return self.acceleration
