"""A simulated battery producing PX4 ``battery_status`` content, for the simulator, as PX4's battery simulator
(``src/modules/simulation/battery_simulator/BatterySimulator.cpp``) makes it.

While armed the charge falls linearly from full to empty over SIM_BAT_DRAIN seconds (0: it does not fall);
disarming refills it. It never falls below SIM_BAT_MIN_PCT (PX4's floor, 50 % by default, so a default run never
reaches a warning; lower it to exercise the battery failsafes).

The simulated pack has no current sensor, as in PX4: the current, its average and the charge drawn are unknown
(-1) and so is the time remaining (NaN). The voltage is the open-circuit voltage of the charge: per cell, linear
in the state of charge between BAT1_V_EMPTY and BAT1_V_CHARGED (PX4's battery model, ``src/lib/battery``).
``remaining`` is the state of charge. The warning level comes from BAT_LOW_THR, BAT_CRIT_THR and BAT_EMERGEN_THR
and, while armed, only ever rises (PX4 keeps the worst warning of a flight).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
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
    bat_low_thr: float
    bat_crit_thr: float
    bat_emergen_thr: float


PARAMS: tuple[Param, ...] = SimBatteryParams.PARAMS

UNKNOWN = -1.0
"""``battery_status``'s value for a current or a charge drawn that no sensor measures."""


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


class BatteryModel:
    """Step with ``update(dt_s, armed)`` from the simulator loop; returns a :class:`BatteryState`."""

    __slots__ = ("_charge", "_p", "_warning")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._charge = 1.0
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

    def update(self, dt_s: float, armed: bool) -> BatteryState:
        p = self._p
        if armed and p.sim_bat_drain > 0.0:
            self._charge -= dt_s / p.sim_bat_drain
        elif not armed:
            self._charge = 1.0
        self._charge = remaining = max(self._charge, p.sim_bat_min_pct / 100.0)
        new_warning = self.warning_for(remaining)
        if not armed or new_warning > self._warning:
            self._warning = new_warning
        return BatteryState(
            connected=True,
            voltage_v=self.open_circuit_voltage(remaining),
            current_a=UNKNOWN,
            current_average_a=UNKNOWN,
            discharged_mah=UNKNOWN,
            remaining=remaining,
            time_remaining_s=math.nan,
            cell_count=p.bat1_n_cells,
            capacity=p.bat1_capacity,
            warning=int(self._warning),
        )
