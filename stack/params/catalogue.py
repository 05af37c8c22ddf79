"""Every parameter of the stack, each defined once, by PX4 parameter group (one module per group).

A module takes the definitions of the parameters it reads from here, by name::

    PARAMS = catalogue.params("MPC_THR_MIN", "MPC_THR_HOVER")

so every module that reads a parameter holds the same definition, and a value one accepts all accept.
``tests/params/test_catalogue.py`` proves that every module's parameters are these objects and that every
parameter here is read by some module: there is none that only ground stations use (one would have to be
documented as such, and exempted there by name).
"""

from __future__ import annotations

from collections.abc import Iterable

from stack.names import suggestion
from stack.params import (
    airspeed,
    atc,
    att_q,
    battery,
    ca,
    commander,
    ekf2,
    fw_att,
    fw_pos,
    geofence,
    hte,
    land_detector,
    lpe,
    mavlink,
    mc_att,
    mc_rate,
    mixer_output,
    mpc,
    navigator,
    pixhawk,
    rotors,
    rtl,
    sensors,
    sim,
    system,
)
from stack.params.param import Param, ParamError

GROUPS = (
    mc_rate,
    mc_att,
    atc,
    mpc,
    land_detector,
    commander,
    system,
    navigator,
    rtl,
    geofence,
    battery,
    att_q,
    lpe,
    ekf2,
    sensors,
    hte,
    ca,
    mixer_output,
    sim,
    pixhawk,
    mavlink,
    rotors,
    fw_att,
    fw_pos,
    airspeed,
)


def _index(groups: Iterable) -> dict[str, Param]:
    index: dict[str, Param] = {}
    for group in groups:
        for p in group.PARAMS:
            if p.name in index:
                raise ValueError(f"parameter {p.name} is defined twice ({group.__name__})")
            index[p.name] = p
    return index


CATALOGUE: dict[str, Param] = _index(GROUPS)


def get(name: str) -> Param:
    """The definition of ``name``; ParamError naming the closest known name if there is none."""
    try:
        return CATALOGUE[name]
    except KeyError:
        raise ParamError(f"unknown parameter '{name}'{suggestion(name, CATALOGUE)}") from None


def params(*names: str) -> tuple[Param, ...]:
    """The definitions of ``names``, in that order (a module's PARAMS)."""
    return tuple(get(name) for name in names)
