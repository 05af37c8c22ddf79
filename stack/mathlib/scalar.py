"""Scalar helpers shared by controllers and estimators (PX4's ``math::`` namespace)."""

from __future__ import annotations

import math

CONSTANTS_ONE_G = 9.80665
FLT_EPSILON = 2.0**-23
"""C's ``FLT_EPSILON`` (single-precision machine epsilon), the threshold PX4 uses for its degenerate checks."""


def is_zero(x: float) -> bool:
    """ArduPilot's ``is_zero`` (AP_Math): within FLT_EPSILON of zero."""
    return abs(x) < FLT_EPSILON


def is_positive(x: float) -> bool:
    """ArduPilot's ``is_positive``: at least FLT_EPSILON."""
    return x >= FLT_EPSILON


def is_negative(x: float) -> bool:
    """ArduPilot's ``is_negative``: at most -FLT_EPSILON."""
    return x <= -FLT_EPSILON


def constrain(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


def wrap_pi(x: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    if -math.pi <= x < math.pi:
        return x
    return (x + math.pi) % (2.0 * math.pi) - math.pi


def sign(x: float) -> float:
    return 1.0 if x > 0.0 else -1.0 if x < 0.0 else 0.0


def expo(x: float, e: float) -> float:
    """PX4 math::expo: blend linear and cubic stick response, e in [0, 1]."""
    x = constrain(x, -1.0, 1.0)
    e = constrain(e, 0.0, 1.0)
    return (1.0 - e) * x + e * x * x * x


def superexpo(x: float, e: float, g: float) -> float:
    """PX4 math::superexpo: expo with an additional 'super rate' factor g in [0, 0.99]."""
    x = constrain(x, -1.0, 1.0)
    g = constrain(g, 0.0, 0.99)
    return expo(x, e) * (1.0 - g) / (1.0 - abs(x) * g)


def deadzone(x: float, dz: float) -> float:
    """PX4 math::deadzone: zero within +-dz, rescaled to reach +-1 at the ends."""
    x = constrain(x, -1.0, 1.0)
    dz = constrain(dz, 0.0, 0.99)
    out = (x - sign(x) * dz) / (1.0 - dz)
    return out if abs(x) > dz else 0.0


def interpolate(x: float, x0: float, x1: float, y0: float, y1: float) -> float:
    """Linear interpolation of x between (x0, y0) and (x1, y1), clamped at the ends."""
    if x <= x0:
        return y0
    if x >= x1:
        return y1
    return y0 + (x - x0) * (y1 - y0) / (x1 - x0)
