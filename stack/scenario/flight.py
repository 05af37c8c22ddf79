"""What ``stack fly`` adds to a profile to fly a scenario: its parameters, the wind, the scenario module.

Both ``stack fly`` (every module its own process) and :mod:`stack.scenario.inprocess` (one process)
prepare a flight here, so a seed flies the same flight either way.
"""

from __future__ import annotations

import json
from pathlib import Path

from stack.runtime.spec import load_module_class
from stack.scenario.catalogue import Check, get_scenario
from stack.supervisor.profile import ModuleEntry, Profile

WIND_SPEED = 5.0
WIND_PARAMS: dict[str, object] = {
    "SIM_WIND_SPD": WIND_SPEED,
    "SIM_WIND_DIR": 270.0,
    "SIM_WIND_GUST": 1.0,
    "SIM_WIND_GUST_T": 2.0,
}
"""``--wind``: a westerly at 5 m/s with gusts of 1 m/s (1 σ) horizontally and half that vertically (the simulator's
rule for SIM_WIND_GUST), 2 s correlation time."""


def prepare_flight(
    prof: Profile,
    scenario: str,
    result_path: Path,
    wind: bool,
    wind_speed: float = WIND_SPEED,
    host: str = "",
    swarm: str = "",
) -> None:
    """Set the scenario's parameters (and the wind's, at ``wind_speed``), and add the scenario module writing
    ``result_path`` with the profile's limits for it (doubled in wind), on ``host`` of a profile spread over several,
    as the vehicle of a swarm flight ``swarm`` says (the module's argument; empty: a flight of one vehicle); a
    parameter no module has is a ValueError."""
    chosen = get_scenario(scenario)
    set_params(prof, chosen.params)
    if wind:
        set_params(prof, {**WIND_PARAMS, "SIM_WIND_SPD": wind_speed})
    limits = dict(prof.scenario_limits.get(scenario, {}))
    if wind:
        limits = windy_limits(chosen.checks, limits)
    add_scenario(prof, scenario, result_path, limits, prof.scenario_options.get(scenario, {}), host, swarm)


def set_params(prof: Profile, params: dict[str, object]) -> None:
    """Set parameters on every module of the profile that has them; one no module has is an error."""
    for name, value in params.items():
        holders = [m for m in prof.modules if any(p.name == name for p in m.cls.PARAMS)]
        if not holders:
            raise ValueError(f"no module of profile {prof.name} has parameter {name}")
        for m in holders:
            m.params[name] = next(p for p in m.cls.PARAMS if p.name == name).check(value)


def windy_limits(checks: tuple[Check, ...], limits: dict[str, object]) -> dict[str, object]:
    """The numeric upper limits doubled (`stack fly --wind`'s rule for flights in wind), others unchanged."""
    out = dict(limits)
    for check in checks:
        limit = out.get(check.metric, check.limit)
        if isinstance(limit, int | float) and not isinstance(limit, bool) and not check.at_least:
            out[check.metric] = 2.0 * limit
    return out


def add_scenario(
    prof: Profile,
    scenario: str,
    result_path: Path,
    limits: dict[str, object],
    options: dict[str, str] | None = None,
    host: str = "",
    swarm: str = "",
) -> None:
    """Append the scenario module to a profile (critical: the stack stops when the scenario ends)."""
    cls = load_module_class("scenario")
    prof.modules.append(
        ModuleEntry(
            name="scenario",
            module="scenario",
            cls=cls,
            params={},
            args={
                "name": scenario,
                "result": str(result_path),
                "limits": json.dumps(limits),
                "options": json.dumps(options or {}),
                "swarm": swarm,
            },
            condition="",
            restart="no",
            max_restarts=0,
            critical=True,
            host=host,
        )
    )
