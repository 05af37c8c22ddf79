"""Discrete filters used by the sensor pipeline and the controllers (PX4's math library)."""

from __future__ import annotations

import math


class LowPassFilter2p:
    """Second-order Butterworth low-pass as a direct-form-II biquad (PX4 ``math::LowPassFilter2p``).

    A cutoff of 0 or at/above Nyquist disables the filter (output = input).
    """

    __slots__ = ("_a1", "_a2", "_b0", "_b1", "_b2", "_d1", "_d2", "_enabled", "cutoff_hz", "sample_hz")

    def __init__(self, sample_hz: float, cutoff_hz: float) -> None:
        self.set_cutoff(sample_hz, cutoff_hz)

    def set_cutoff(self, sample_hz: float, cutoff_hz: float) -> None:
        self.sample_hz = sample_hz
        self.cutoff_hz = cutoff_hz
        self._d1 = self._d2 = 0.0
        self._enabled = sample_hz > 0.0 and 0.0 < cutoff_hz < 0.5 * sample_hz
        if not self._enabled:
            self._b0, self._b1, self._b2, self._a1, self._a2 = 1.0, 0.0, 0.0, 0.0, 0.0
            return
        fr = sample_hz / cutoff_hz
        ohm = math.tan(math.pi / fr)
        c = 1.0 + 2.0 * math.cos(math.pi / 4.0) * ohm + ohm * ohm
        self._b0 = ohm * ohm / c
        self._b1 = 2.0 * self._b0
        self._b2 = self._b0
        self._a1 = 2.0 * (ohm * ohm - 1.0) / c
        self._a2 = (1.0 - 2.0 * math.cos(math.pi / 4.0) * ohm + ohm * ohm) / c

    def apply(self, x: float) -> float:
        if not self._enabled:
            return x
        d0 = x - self._d1 * self._a1 - self._d2 * self._a2
        if not math.isfinite(d0):
            d0 = x
        y = d0 * self._b0 + self._d1 * self._b1 + self._d2 * self._b2
        self._d2 = self._d1
        self._d1 = d0
        return y

    def reset(self, x: float) -> float:
        """Set the state so a constant input x passes through unchanged."""
        if not self._enabled:
            return x
        d = x / (self._b0 + self._b1 + self._b2)
        self._d1 = self._d2 = d
        return self.apply(x)


class AlphaFilter:
    """First-order low-pass y += alpha·(x − y) (PX4 ``AlphaFilter``), set from a cutoff frequency."""

    __slots__ = ("_alpha", "_initialised", "state")

    def __init__(self, sample_hz: float = 0.0, cutoff_hz: float = 0.0) -> None:
        self.state = 0.0
        self._initialised = False
        self._alpha = 1.0
        if sample_hz > 0.0:
            self.set_cutoff(sample_hz, cutoff_hz)

    def set_cutoff(self, sample_hz: float, cutoff_hz: float) -> None:
        if cutoff_hz <= 0.0 or sample_hz <= 0.0:
            self._alpha = 1.0
            return
        dt = 1.0 / sample_hz
        rc = 1.0 / (2.0 * math.pi * cutoff_hz)
        self._alpha = dt / (rc + dt)

    def set_time_constant(self, dt: float, tau: float) -> None:
        self._alpha = dt / (tau + dt) if tau > 0.0 else 1.0

    def update(self, x: float) -> float:
        if not self._initialised:
            self.state = x
            self._initialised = True
        else:
            self.state += self._alpha * (x - self.state)
        return self.state

    def reset(self, x: float) -> None:
        self.state = x
        self._initialised = True


class SlewRate:
    """Rate-of-change limiter (PX4 ``SlewRate``): the state moves toward each new value by at most
    ``slew_rate · dt`` per update."""

    __slots__ = ("slew_rate", "state")

    def __init__(self, slew_rate: float, initial: float = 0.0) -> None:
        self.slew_rate = slew_rate
        self.state = initial

    def set_forced_value(self, value: float) -> None:
        self.state = value

    def update(self, target: float, dt: float) -> float:
        step = self.slew_rate * dt
        delta = target - self.state
        self.state += step if delta > step else -step if delta < -step else delta
        return self.state
