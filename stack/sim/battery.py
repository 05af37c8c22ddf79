"""A simulated battery producing PX4 ``battery_status`` content, for the simulator.

Two ways to discharge:

* **Timed drain** (PX4 ``battery_simulator``, ``BatterySimulator.cpp``): while armed the charge falls
  linearly from full to empty over SIM_BAT_DRAIN seconds; disarming refills it. The reported current is the
  one that empties BAT1_CAPACITY in that time. This is what ``update(dt, armed)`` does.
* **Electrical drain**: ``update(dt, armed, current_a)`` integrates the current the motors draw (see
  :func:`motor_current`) against BAT1_CAPACITY; nothing refills the pack.

Either way the charge never falls below SIM_BAT_MIN_PCT (PX4's floor, 50 % by default, so a default run
never reaches a warning; lower it to exercise the battery failsafes).

The pack voltage follows PX4's battery model (``src/lib/battery``): per cell, the open-circuit voltage is
linear in the state of charge between BAT1_V_EMPTY and BAT1_V_CHARGED, less the load drop
current × BAT1_R_INTERNAL. ``remaining`` is the state of charge, which is what PX4's load-compensated
voltage estimate recovers from that model. The warning level comes from BAT_LOW_THR, BAT_CRIT_THR and
BAT_EMERGEN_THR and, while armed, only ever rises (PX4 keeps the worst warning of a flight).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import NamedTuple

from stack.msg.system import BatteryWarning
from stack.params.binding import ParamSet
from stack.params.param import Param

PERIOD_US = 100_000
"""How often the simulated battery is stepped and published (PX4's battery_status at 10 Hz)."""


class SimBatteryParams(ParamSet):
    """The simulated pack (the catalogue's BAT*), its warning thresholds and the simulator's drain."""

    sim_bat_drain: float
    sim_bat_min_pct: float
    bat1_n_cells: int
    bat1_capacity: float
    bat1_v_empty: float
    bat1_v_charged: float
    bat1_r_internal: float
    bat_low_thr: float
    bat_crit_thr: float
    bat_emergen_thr: float


PARAMS: tuple[Param, ...] = SimBatteryParams.PARAMS

AVERAGE_CURRENT_TAU = 2.0
"""Time constant [s] of the average current used for the time-remaining estimate."""
AIR_DENSITY = 1.225
"""Sea-level air density [kg/m³]."""


class BatteryState(NamedTuple):
    """``battery_status`` content (PX4 field names; ``capacity`` in mAh, ``remaining`` in [0, 1])."""

    connected: bool
    voltage_v: float
    current_a: float
    current_average_a: float
    discharged_mah: float
    remaining: float
    time_remaining_s: float
    cell_count: int
    capacity: float
    warning: int


def motor_current(
    thrusts_n: Iterable[float],
    voltage_v: float,
    rotor_radius_m: float,
    figure_of_merit: float = 0.65,
    drive_efficiency: float = 0.8,
    avionics_current_a: float = 0.5,
) -> float:
    """Current [A] drawn to produce the given rotor thrusts, from momentum theory.

    Each rotor's ideal induced power is T^1.5 / √(2ρA) (A = disc area); dividing by the rotor's figure of
    merit and the motor-and-ESC efficiency gives electrical power. ``avionics_current_a`` is the constant
    draw of everything else."""
    disc_factor = math.sqrt(2.0 * AIR_DENSITY * math.pi * rotor_radius_m * rotor_radius_m)
    power = 0.0
    for thrust in thrusts_n:
        if thrust > 0.0:
            power += thrust * math.sqrt(thrust) / disc_factor
    return power / (figure_of_merit * drive_efficiency * voltage_v) + avionics_current_a


class BatteryModel:
    """Step with ``update(dt_s, armed[, current_a])`` from the simulator loop; returns a :class:`BatteryState`."""

    __slots__ = ("_average_a", "_charge", "_discharged_mah", "_p", "_warning")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._charge = 1.0
        self._discharged_mah = 0.0
        self._average_a = 0.0
        self._warning = BatteryWarning.NONE
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = SimBatteryParams.from_params(params)

    def open_circuit_voltage(self, state_of_charge: float) -> float:
        """Pack voltage [V] with no load at the given state of charge."""
        p = self._p
        cell = p.bat1_v_empty + state_of_charge * (p.bat1_v_charged - p.bat1_v_empty)
        return cell * p.bat1_n_cells

    def warning_for(self, remaining: float) -> BatteryWarning:
        p = self._p
        if remaining < p.bat_emergen_thr:
            return BatteryWarning.EMERGENCY
        if remaining < p.bat_crit_thr:
            return BatteryWarning.CRITICAL
        if remaining < p.bat_low_thr:
            return BatteryWarning.LOW
        return BatteryWarning.NONE

    def update(self, dt_s: float, armed: bool, current_a: float = math.nan) -> BatteryState:
        p = self._p
        capacity = p.bat1_capacity
        floor = p.sim_bat_min_pct / 100.0
        drain_s = p.sim_bat_drain
        if math.isfinite(current_a):
            current = max(current_a, 0.0)
            if self._charge > floor:
                self._discharged_mah += current * dt_s / 3.6
            self._charge = max(1.0 - self._discharged_mah / capacity, floor)
        elif armed and drain_s > 0.0:
            current = capacity * 3.6 / drain_s
            self._charge = max(self._charge - dt_s / drain_s, floor)
            self._discharged_mah = (1.0 - self._charge) * capacity
        else:
            current = 0.0
            if drain_s > 0.0:
                self._charge = 1.0
                self._discharged_mah = 0.0

        alpha = dt_s / (AVERAGE_CURRENT_TAU + dt_s) if dt_s > 0.0 else 0.0
        self._average_a += alpha * (current - self._average_a)

        remaining = self._charge
        new_warning = self.warning_for(remaining)
        if not armed or new_warning > self._warning:
            self._warning = new_warning

        voltage = self.open_circuit_voltage(remaining) - current * p.bat1_r_internal * p.bat1_n_cells
        time_remaining = remaining * capacity * 3.6 / self._average_a if self._average_a > 0.1 else math.nan
        return BatteryState(
            connected=True,
            voltage_v=voltage,
            current_a=current,
            current_average_a=self._average_a,
            discharged_mah=self._discharged_mah,
            remaining=remaining,
            time_remaining_s=time_remaining,
            cell_count=p.bat1_n_cells,
            capacity=capacity,
            warning=int(self._warning),
        )
