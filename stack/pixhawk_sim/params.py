"""The simulated Pixhawk's parameters: PX4's names, with the stack's definition (``stack.params.catalogue``)
wherever the stack has the parameter.

The controllers, the allocator, the land detector and the battery bring their own parameter tables; the
commander's timeouts, the Offboard-loss action and the failure detector's attitude limits come from the
catalogue's commander group. The airframe geometry (``CA_ROTOR*``, ``THR_MDL_FAC``, ``MPC_THR_HOVER``) comes
from the vehicle model, as a launch profile's ``airframe`` gives it to the allocator.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path

from stack.airframe.model import VehicleModel
from stack.attctl import attitude_control, rate_control
from stack.commander import land_detector, offboard
from stack.commander import state_machine as commander
from stack.estimator.angular_velocity import GyroFilterParams
from stack.mixer import allocation, effectiveness, output
from stack.params import catalogue
from stack.params.binding import combine
from stack.params.param import Param, ParamError, ParamValue
from stack.posctl import flight_mode_manager, pos_module
from stack.sim import battery

_COMMANDER_NAMES = ("COM_DISARM_LAND", "COM_DISARM_PRFLT")
_SIMULATOR_NAMES = ("SIH_LOC_LAT0", "SIH_LOC_LON0", "SIH_LOC_H0")


# The first definition of each name (the land detector repeats a few MPC_* of position control).
AUTOPILOT_PARAMS: tuple[Param, ...] = combine(
    catalogue.params("COM_OBL_RC_ACT", "FD_FAIL_R", "FD_FAIL_P"),
    offboard.PARAMS,
    (p for p in commander.PARAMS if p.name in _COMMANDER_NAMES),
    GyroFilterParams.PARAMS,
    rate_control.PARAMS,
    attitude_control.PARAMS,
    pos_module.PARAMS,
    flight_mode_manager.PARAMS,
    land_detector.PARAMS,
    effectiveness.PARAMS,
    allocation.PARAMS,
    output.PARAMS,
)
"""The autopilot's: its commander (``Px4Commander``), land detector and control chain (``FlightControl``), which
the simulator's takeover on a silent flight stack (``stack.sim.command_loss``) flies too."""
PARAMS: tuple[Param, ...] = combine(AUTOPILOT_PARAMS, catalogue.params(*_SIMULATOR_NAMES), battery.PARAMS)
DEFINITIONS: dict[str, Param] = {p.name: p for p in PARAMS}


def parameter_values(vehicle: VehicleModel, overrides: Mapping[str, object] | None = None) -> dict[str, ParamValue]:
    """Defaults, then the vehicle's airframe table, then ``overrides``; each value checked against its definition.

    An unknown name in ``overrides`` is an error (ParamError naming it)."""
    values: dict[str, ParamValue] = {p.name: p.default for p in PARAMS}
    for name, value in vehicle.airframe.items():
        if name in DEFINITIONS:
            values[name] = DEFINITIONS[name].check(value)
    for name, value in (overrides or {}).items():
        if name not in DEFINITIONS:
            raise ParamError(f"unknown parameter '{name}' (the simulated Pixhawk does not use it)")
        values[name] = DEFINITIONS[name].check(value)
    return values


def read_params_file(path: Path) -> tuple[dict[str, object], list[str]]:
    """The ``[params]`` table of a TOML file (a launch profile qualifies): (the values this Pixhawk uses, the
    names it does not use, which a launch profile has for the stack's other modules)."""
    with path.open("rb") as f:
        table = tomllib.load(f).get("params", {})
    if not isinstance(table, dict):
        raise ParamError(f"{path}: [params] is not a table")
    used = {name: value for name, value in table.items() if name in DEFINITIONS}
    return used, sorted(name for name in table if name not in DEFINITIONS)
