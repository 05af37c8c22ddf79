"""Step-response and tracking metrics computed from sampled signals (plain functions, no I/O)."""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from typing import Any


def step_response(
    times: Sequence[float], values: Sequence[float], t_step: float, start: float, target: float, window: float = 1.2
) -> tuple[float, float]:
    """10 %–90 % rise time [s] and overshoot [% of the step] of a step from ``start`` to ``target`` at ``t_step``.

    Crossing times are interpolated between samples, so the result does not depend on the sample grid.
    The rise time is NaN if the signal does not reach 90 % within ``window`` seconds.
    """
    span = target - start
    if span == 0.0:
        raise ValueError("a step needs a non-zero size")
    t10 = t90 = math.nan
    peak = 0.0
    prev: tuple[float, float] | None = None
    for t, v in zip(times, values, strict=True):
        if t < t_step:
            continue
        if t > t_step + window:
            break
        r = (v - start) / span
        if prev is not None:
            pt, pr = prev
            if math.isnan(t10) and pr < 0.1 <= r:
                t10 = pt + (0.1 - pr) / (r - pr) * (t - pt)
            if math.isnan(t90) and pr < 0.9 <= r:
                t90 = pt + (0.9 - pr) / (r - pr) * (t - pt)
        prev = (t, r)
        peak = max(peak, r)
    return t90 - t10, max(0.0, (peak - 1.0) * 100.0)


def value_at(times: Sequence[float], values: Sequence[Any], t: float) -> Any:
    """The last sample at or before ``t`` (the first sample if ``t`` precedes them all)."""
    i = bisect.bisect_right(times, t) - 1
    return values[max(i, 0)]


def rms(values: Sequence[float]) -> float:
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else math.nan


def unwrap_degrees(values: Sequence[float]) -> list[float]:
    """Remove ±360° jumps from an angle series in degrees."""
    out: list[float] = []
    offset = 0.0
    for v in values:
        if out:
            d = v + offset - out[-1]
            if d > 180.0:
                offset -= 360.0
            elif d < -180.0:
                offset += 360.0
        out.append(v + offset)
    return out


def time_optimal_rise(angle: float, max_acceleration: float, motor_tau: float, overshoot: float = 0.0) -> float:
    """The shortest possible 10–90 % rise of a rest-to-rest rotation by ``angle`` [rad].

    The plant is a double integrator driven at ±``max_acceleration`` [rad/s²] through a first-order
    actuator lag ``motor_tau`` [s] (a multicopter axis): full effort one way, then the other
    (bang-bang), with the switch chosen so the peak is ``angle·(1 + overshoot)``. No controller can
    rise faster, so this bounds what a step-response target can ask of a vehicle.
    """

    def simulate(t_switch: float) -> tuple[float, list[tuple[float, float]]]:
        dt = 2e-5
        alpha = 1.0 - math.exp(-dt / motor_tau) if motor_tau > 0 else 1.0
        a = w = th = t = 0.0
        trace = []
        while True:
            command = max_acceleration if t < t_switch else -max_acceleration
            a += (command - a) * alpha
            w += a * dt
            th += w * dt
            t += dt
            trace.append((t, th))
            if t > t_switch and w <= 0.0:
                return th, trace

    peak_wanted = angle * (1.0 + overshoot)
    lo, hi = 0.0, 10.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if simulate(mid)[0] < peak_wanted:
            lo = mid
        else:
            hi = mid
    _, trace = simulate(lo)
    times = [t for t, _ in trace]
    values = [th for _, th in trace]
    rise, _ = step_response(times, values, 0.0, 0.0, angle, window=math.inf)
    return rise
