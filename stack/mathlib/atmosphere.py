"""The ISA standard atmosphere (troposphere): pressure ↔ altitude, as barometer drivers and simulators use it."""

from __future__ import annotations

from stack.mathlib.scalar import CONSTANTS_ONE_G

ISA_SEA_LEVEL_PRESSURE_PA = 101325.0
AIR_DENSITY_SEA_LEVEL = 1.225  # kg/m³, PX4 CONSTANTS_AIR_DENSITY_SEA_LEVEL_15C
ISA_SEA_LEVEL_TEMPERATURE_K = 288.15
ISA_LAPSE_RATE_K_PER_M = 0.0065
ISA_GAS_CONSTANT_AIR = 287.05287  # J/(kg·K)
ISA_PRESSURE_EXPONENT = CONSTANTS_ONE_G / (ISA_GAS_CONSTANT_AIR * ISA_LAPSE_RATE_K_PER_M)  # ≈ 5.2559


def isa_temperature_k(altitude_msl: float) -> float:
    """ISA troposphere temperature (K) at an altitude above mean sea level (m)."""
    return ISA_SEA_LEVEL_TEMPERATURE_K - ISA_LAPSE_RATE_K_PER_M * altitude_msl


def isa_pressure_pa(altitude_msl: float) -> float:
    """ISA troposphere static pressure (Pa) at an altitude above mean sea level (m)."""
    return ISA_SEA_LEVEL_PRESSURE_PA * (isa_temperature_k(altitude_msl) / ISA_SEA_LEVEL_TEMPERATURE_K) ** (
        ISA_PRESSURE_EXPONENT
    )


def isa_altitude_m(pressure_pa: float) -> float:
    """Altitude AMSL (m) at which the ISA troposphere has this pressure (inverse of ``isa_pressure_pa``)."""
    ratio = (pressure_pa / ISA_SEA_LEVEL_PRESSURE_PA) ** (1.0 / ISA_PRESSURE_EXPONENT)
    return ISA_SEA_LEVEL_TEMPERATURE_K / ISA_LAPSE_RATE_K_PER_M * (1.0 - ratio)
