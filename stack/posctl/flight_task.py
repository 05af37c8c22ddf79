"""What every flight task shares: the vehicle state it reads, the setpoint it produces, and heading control.

A flight task (PX4 ``FlightTask``) turns the current mode into a ``trajectory_setpoint`` for the position
controller. Components are NED; NaN means "not controlled" in a setpoint and "not known" in the state.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.scalar import wrap_pi
from stack.mathlib.vector import NAN3, Vec3

NAN = math.nan


class VehicleState(NamedTuple):
    """The estimate a flight task works from (position or velocity components NaN when invalid)."""

    now_us: int
    position: Vec3
    velocity: Vec3
    yaw: float
    landed: bool
    flying: bool
    """The position controller finished its takeoff (PX4 takeoff state "flight")."""


class TrajectoryCommand(NamedTuple):
    """A ``trajectory_setpoint``: kinematic setpoints (feed-forward where a lower derivative is set) and yaw."""

    position: Vec3 = NAN3
    velocity: Vec3 = NAN3
    acceleration: Vec3 = NAN3
    jerk: Vec3 = NAN3
    yaw: float = NAN
    yawspeed: float = NAN


def stopping_point(position: Vec3, velocity: Vec3, max_accel: float) -> Vec3:
    """Where the vehicle comes to rest braking horizontally at ``max_accel`` (it keeps its altitude)."""
    vx, vy = velocity[0], velocity[1]
    if not (math.isfinite(vx) and math.isfinite(vy)) or max_accel <= 0.0:
        return position
    speed = math.hypot(vx, vy)
    distance_per_speed = speed / (2.0 * max_accel)
    return (position[0] + vx * distance_per_speed, position[1] + vy * distance_per_speed, position[2])


class YawSlew:
    """A heading setpoint that turns toward its target no faster than a rate limit (MPC_YAWRAUTO_MAX)."""

    __slots__ = ("yaw",)

    def __init__(self) -> None:
        self.yaw = NAN

    def reset(self, yaw: float) -> None:
        self.yaw = yaw

    def update(self, target: float, dt: float, max_rate: float) -> tuple[float, float]:
        """(yaw, yawspeed) one step closer to ``target``; a NaN target holds the current setpoint."""
        if not math.isfinite(self.yaw):
            self.yaw = target
            return target, 0.0 if math.isfinite(target) else NAN
        if not math.isfinite(target) or dt <= 0.0:
            return self.yaw, 0.0
        error = wrap_pi(target - self.yaw)
        step = max(-max_rate * dt, min(max_rate * dt, error))
        self.yaw = wrap_pi(self.yaw + step)
        return self.yaw, step / dt
