"""The state accessors every rigid-body plant shares (the multicopter's and the airplane's physics)."""

from __future__ import annotations

from stack.mathlib.quaternion import Quat, rotate_inv
from stack.mathlib.vector import ZERO3, Vec3


class RigidBodyState:
    """Position, velocity, attitude and rates of a plant, and the accelerations over its last step.

    A subclass keeps ``_position``, ``_velocity``, ``_attitude``, ``_angular_velocity`` (and their values before
    the last step, ``_previous_velocity`` and ``_previous_angular_velocity``), ``_last_dt``, ``_gravity`` and
    ``_on_ground``.
    """

    __slots__ = ()
    _position: Vec3
    _velocity: Vec3
    _attitude: Quat
    _angular_velocity: Vec3
    _previous_velocity: Vec3
    _previous_angular_velocity: Vec3
    _last_dt: float
    _gravity: float
    _on_ground: bool

    @property
    def position(self) -> Vec3:
        """NED position about home (m)."""
        return self._position

    @property
    def velocity(self) -> Vec3:
        """NED velocity (m/s)."""
        return self._velocity

    @property
    def attitude(self) -> Quat:
        """Body FRD → NED quaternion."""
        return self._attitude

    @property
    def angular_velocity(self) -> Vec3:
        """Body rates FRD (rad/s)."""
        return self._angular_velocity

    @property
    def on_ground(self) -> bool:
        """Whether the plant touched the ground in the last step."""
        return self._on_ground

    @property
    def gravity(self) -> float:
        """Gravitational acceleration used by the model (m/s², NED +z)."""
        return self._gravity

    @property
    def acceleration(self) -> Vec3:
        """Mean acceleration NED over the last step (m/s²); zero before the first step."""
        dt = self._last_dt
        if dt <= 0.0:
            return ZERO3
        v, p = self._velocity, self._previous_velocity
        return ((v[0] - p[0]) / dt, (v[1] - p[1]) / dt, (v[2] - p[2]) / dt)

    @property
    def angular_acceleration(self) -> Vec3:
        """Mean angular acceleration FRD over the last step (rad/s²)."""
        dt = self._last_dt
        if dt <= 0.0:
            return ZERO3
        w, p = self._angular_velocity, self._previous_angular_velocity
        return ((w[0] - p[0]) / dt, (w[1] - p[1]) / dt, (w[2] - p[2]) / dt)

    @property
    def specific_force(self) -> Vec3:
        """What an ideal accelerometer reads, in body FRD (m/s²): Rᵀ·(a − g); (0, 0, −g) at rest level."""
        ax, ay, az = self.acceleration
        return rotate_inv(self._attitude, (ax, ay, az - self._gravity))
