"""Simulator ground truth: the true state of the simulated vehicle, for metrics and plots."""

from __future__ import annotations

from stack.msg.base import F3, F4, NAN, Q_IDENTITY, ZERO3, Message


class SimGroundtruth(Message):
    """True kinematic state (NED about the home point, body FRD) and the environment the plant saw."""

    timestamp_sample: int = 0
    position: F3 = ZERO3
    velocity: F3 = ZERO3
    acceleration: F3 = ZERO3
    q: F4 = Q_IDENTITY
    angular_velocity: F3 = ZERO3
    angular_acceleration: F3 = ZERO3
    lat: float = NAN
    lon: float = NAN
    alt: float = NAN
    on_ground: bool = True
    wind: F3 = ZERO3
    motors: tuple[float, ...] = ()
