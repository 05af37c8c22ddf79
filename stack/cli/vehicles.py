"""``stack vehicles``: every vehicle on the bus with its state, as QGroundControl's vehicle list shows them.

The bus is the one of ``--endpoint``, else of the stacks running on this machine that a command naming no stack
addresses (stacks joined into one bus list the same vehicles, each once). A vehicle is on the bus when its
supervisors answer; its state comes from its own messages, as in ``stack status``.
"""

from __future__ import annotations

import json
import math
import os
from contextlib import ExitStack
from typing import Any

import typer

from stack.bus.node import Node
from stack.bus.supervisors import vehicles_status
from stack.cli import vehicle_summary
from stack.cli.common import EndpointOption, JsonOption, bus_configs, open_bus, print_table, to_jsonable


def vehicles(endpoint: str | None = EndpointOption, as_json: bool = JsonOption) -> None:
    """Every vehicle on the bus: mode, armed, position, battery and its modules running."""
    found: dict[str, dict[str, Any]] = {}
    tool = f"cli-{os.getpid()}"
    with ExitStack() as stack:
        for bus in bus_configs(endpoint):
            session = open_bus(bus, tool)
            stack.callback(session.close)
            reports = {v: r for v, r in vehicles_status(session).items() if v not in found}
            nodes = [stack.enter_context(Node(bus, v, tool, stable_id=False, session=session)) for v in reports]
            vehicle_summary.add_summaries(reports, nodes)
            for vehicle, report in reports.items():
                found[vehicle] = _row(vehicle, report)
    rows = [found[v] for v in sorted(found)]
    if as_json:
        typer.echo(json.dumps(to_jsonable(rows)))
        return
    if not rows:
        typer.echo("no vehicle on the bus")
        return
    print_table(
        ("VEHICLE", "PROFILE", "MODE", "ARMED", "NORTH", "EAST", "ALT", "BATTERY", "MODULES"),
        [_cells(r) for r in rows],
    )


def _row(vehicle: str, report: dict[str, Any]) -> dict[str, Any]:
    modules = report.get("modules", [])
    return {
        "vehicle": vehicle,
        "profile": report.get("profile", ""),
        "lockstep": bool(report.get("lockstep")),
        "hosts": report.get("hosts", []),
        "modules": len(modules),
        "modules_running": sum(1 for m in modules if m.get("state") == "running"),
        "modules_not_running": {str(m.get("module")): m.get("state") for m in modules if m.get("state") != "running"},
        **report.get("vehicle_summary", {}),
    }


def _cells(r: dict[str, Any]) -> tuple[str, ...]:
    p, b = r.get("position"), r.get("battery")
    armed = "-" if "armed" not in r else "yes" if r["armed"] else "no"
    battery = "-" if b is None or b["remaining"] < 0 else f"{b['remaining'] * 100:.0f}%"
    return (
        r["vehicle"],
        str(r["profile"]),
        r.get("mode", "-"),
        armed,
        _metres(p["north"]) if p else "-",
        _metres(p["east"]) if p else "-",
        _metres(p["altitude_above_home"]) if p else "-",
        battery,
        f"{r['modules_running']}/{r['modules']}",
    )


def _metres(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.1f}"
