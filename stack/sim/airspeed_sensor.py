"""The simulated differential-pressure airspeed sensor (PX4 ``src/modules/simulation/sensor_airspeed_sim``).

The pitot tube points along body x: it measures the dynamic pressure of the air-relative velocity's
forward component, q = ½·ρ·u²·sign(u), plus white noise (PX4: 0.01 hPa = 1 Pa) and an offset. The
indicated airspeed is the speed that dynamic pressure means at sea-level density, IAS = √(2|q|/ρ₀);
the true airspeed corrects it to the density at the altitude, TAS = IAS·√(ρ₀/ρ) (PX4's
``calc_IAS`` / ``calc_TAS_from_CAS``, with CAS = IAS for a perfect installation).
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import NamedTuple

from stack.mathlib.atmosphere import AIR_DENSITY_SEA_LEVEL, ISA_GAS_CONSTANT_AIR, isa_pressure_pa, isa_temperature_k

KELVIN_OFFSET = 273.15


def air_density(altitude_msl: float) -> float:
    """ISA air density (kg/m³) at an altitude above mean sea level."""
    return isa_pressure_pa(altitude_msl) / (ISA_GAS_CONSTANT_AIR * isa_temperature_k(altitude_msl))


class AirspeedSample(NamedTuple):
    time_us: int
    indicated_airspeed: float  # m/s, signed as the measured pressure
    true_airspeed: float  # m/s
    differential_pressure: float  # Pa
    temperature: float  # °C


@dataclass(frozen=True, slots=True)
class AirspeedParams:
    """Noise and offset of the differential pressure (Pa), and the sample rate (PX4: 20 Hz)."""

    noise_pa: float = 1.0
    offset_pa: float = 0.0
    rate_hz: float = 20.0


class AirspeedModel:
    """Dynamic pressure of the forward air-relative speed, then IAS and TAS from it."""

    __slots__ = ("_gauss", "params")

    def __init__(self, params: AirspeedParams, rng: random.Random) -> None:
        self.params = params
        self._gauss = rng.gauss

    def sample(self, time_us: int, forward_airspeed: float, altitude_msl: float) -> AirspeedSample:
        """Measure at ``forward_airspeed`` (m/s, the air-relative velocity along body x) and this altitude."""
        rho = air_density(altitude_msl)
        p = self.params
        pressure = math.copysign(0.5 * rho * forward_airspeed * forward_airspeed, forward_airspeed)
        pressure += p.offset_pa + p.noise_pa * self._gauss(0.0, 1.0)
        indicated = math.copysign(math.sqrt(2.0 * abs(pressure) / AIR_DENSITY_SEA_LEVEL), pressure)
        true = indicated * math.sqrt(AIR_DENSITY_SEA_LEVEL / rho)
        return AirspeedSample(time_us, indicated, true, pressure, isa_temperature_k(altitude_msl) - KELVIN_OFFSET)
