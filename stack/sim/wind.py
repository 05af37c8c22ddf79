"""Wind for the simulated plant: a mean wind plus gusts from a seeded Gauss–Markov process per axis.

Each axis of the gust velocity is a first-order Gauss–Markov process (the simplest Dryden-like
turbulence: exponential autocorrelation σ²·exp(−|t|/τ)), discretised exactly for any step:
g ← exp(−dt/τ)·g + σ·√(1 − exp(−2·dt/τ))·N(0, 1). The process starts from its stationary
distribution, so its statistics do not depend on how long the simulation has run.

Near the ground the wind may follow the neutral atmospheric surface layer's logarithmic profile
(``reference_height`` > 0): u(h) = u_ref·ln(h/z₀)/ln(h_ref/z₀) below the reference height, none at or below
the roughness length z₀ (0.03 m, open flat terrain with grass: the Davenport–Wieringa roughness class "open";
J. Wieringa, "Updating the Davenport roughness classification", J. Wind Eng. 1992). A plane standing on its
wheels then feels the light breeze it would on a runway, not the full wind aloft. With ``reference_height``
0 the wind is the same at every height.

ArduPilot's SITL names the same figures SIM_WIND_SPD, SIM_WIND_DIR (the direction the wind comes
from), SIM_WIND_DIR_Z and SIM_WIND_TURB; :meth:`WindParams.from_speed_direction` takes that form.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from stack.mathlib.vector import ZERO3, Vec3

ROUGHNESS_LENGTH = 0.03
"""z₀ of open flat terrain with grass [m] (see the module docstring)."""


def surface_layer_factor(height: float, reference_height: float) -> float:
    """u(h)/u_ref of the logarithmic profile: 0 at or below z₀, 1 at and above the reference height."""
    if reference_height <= 0.0 or height >= reference_height:
        return 1.0
    if not height > ROUGHNESS_LENGTH:
        return 0.0
    return math.log(height / ROUGHNESS_LENGTH) / math.log(reference_height / ROUGHNESS_LENGTH)


@dataclass(frozen=True, slots=True)
class WindParams:
    """Wind figures.

    ``mean_ned``: mean air velocity NED (m/s; the direction the air moves to).
    ``gust_std_horizontal`` / ``gust_std_vertical``: gust standard deviation per axis (m/s, ≥ 0).
    ``gust_time_constant``: gust correlation time τ (s, > 0).
    ``enabled``: initial on/off state; off means exactly zero wind at no cost.
    ``reference_height``: the height above ground the figures hold at, with the logarithmic profile below it
    (m; 0: the same wind at every height).
    """

    mean_ned: Vec3 = ZERO3
    gust_std_horizontal: float = 0.0
    gust_std_vertical: float = 0.0
    gust_time_constant: float = 2.0
    enabled: bool = True
    reference_height: float = 0.0

    def __post_init__(self) -> None:
        if len(self.mean_ned) != 3 or not all(math.isfinite(c) for c in self.mean_ned):
            raise ValueError("mean_ned must be 3 finite numbers")
        object.__setattr__(self, "mean_ned", tuple(float(c) for c in self.mean_ned))
        if not (self.gust_std_horizontal >= 0.0 and self.gust_std_vertical >= 0.0):
            raise ValueError("gust standard deviations must be >= 0")
        if not self.gust_time_constant > 0.0:
            raise ValueError("gust_time_constant must be > 0")
        if not self.reference_height >= 0.0:
            raise ValueError("reference_height must be >= 0")

    @classmethod
    def from_speed_direction(
        cls, speed: float, direction_from_deg: float, vertical_speed: float = 0.0, **gusts: float
    ) -> WindParams:
        """Mean wind of ``speed`` m/s blowing *from* ``direction_from_deg`` (0 = north, 90 = east).

        ``vertical_speed`` is positive down (NED). Gust figures pass through as keyword arguments.
        """
        heading = math.radians(direction_from_deg)
        mean = (-speed * math.cos(heading), -speed * math.sin(heading), vertical_speed)
        return cls(mean_ned=mean, **gusts)

    @property
    def is_calm(self) -> bool:
        return self.mean_ned == ZERO3 and self.gust_std_horizontal == 0.0 and self.gust_std_vertical == 0.0


class WindModel:
    """Seeded wind process; :meth:`update` advances it and returns the wind NED (m/s)."""

    __slots__ = ("_calm", "_dt", "_enabled", "_gust", "_phi", "_rng", "_scale", "_wind", "params")

    def __init__(self, params: WindParams, rng: random.Random) -> None:
        self.params = params
        self._rng = rng
        self._enabled = params.enabled
        self._calm = params.is_calm
        sigma = (params.gust_std_horizontal, params.gust_std_horizontal, params.gust_std_vertical)
        self._gust = tuple(s * rng.gauss(0.0, 1.0) if s > 0.0 else 0.0 for s in sigma)
        self._dt = -1.0
        self._phi = 0.0
        self._scale = ZERO3
        self._wind = self._sum()

    @property
    def enabled(self) -> bool:
        return self._enabled

    def set_enabled(self, enabled: bool) -> None:
        """Switch the wind on or off (off: zero wind, the gust process is frozen)."""
        self._enabled = enabled
        self._wind = self._sum()

    def set_params(self, params: WindParams) -> None:
        """Change the wind figures while running; the gust state carries on from where it is."""
        self.params = params
        self._enabled = params.enabled
        self._calm = params.is_calm
        self._dt = -1.0
        self._wind = self._sum()

    @property
    def wind(self) -> Vec3:
        """The current wind NED (m/s)."""
        return self._wind

    def _sum(self) -> Vec3:
        if not self._enabled:
            return ZERO3
        m, g = self.params.mean_ned, self._gust
        return (m[0] + g[0], m[1] + g[1], m[2] + g[2])

    def at_height(self, height: float) -> Vec3:
        """The current wind at ``height`` above ground (m), on the surface layer's profile."""
        k = surface_layer_factor(height, self.params.reference_height)
        w = self._wind
        return w if k == 1.0 else (k * w[0], k * w[1], k * w[2])

    def update(self, dt: float) -> Vec3:
        """Advance the gusts by dt seconds and return the new wind NED (m/s) aloft (see :meth:`at_height`)."""
        if not self._enabled or self._calm:
            return self._wind
        p = self.params
        if dt != self._dt:
            self._phi = math.exp(-dt / p.gust_time_constant)
            root = math.sqrt(1.0 - self._phi * self._phi)
            self._scale = (p.gust_std_horizontal * root, p.gust_std_horizontal * root, p.gust_std_vertical * root)
            self._dt = dt
        phi = self._phi
        gauss = self._rng.gauss
        gn, ge, gd = self._gust
        sn, se, sd = self._scale
        self._gust = (
            phi * gn + sn * gauss(0.0, 1.0) if sn else 0.0,
            phi * ge + se * gauss(0.0, 1.0) if se else 0.0,
            phi * gd + sd * gauss(0.0, 1.0) if sd else 0.0,
        )
        self._wind = self._sum()
        return self._wind
