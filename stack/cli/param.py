"""``stack param``: list, get and set module parameters of a running stack (like PX4's ``param``)."""

from __future__ import annotations

import fnmatch
import json

import typer

from stack.bus import keys
from stack.cli.common import EndpointOption, JsonOption, VehicleOption, connect, fail, print_table, query_json

app = typer.Typer(help="Read and change parameters of the running modules.", no_args_is_help=True)


def _all_params(session, vehicle: str) -> list[dict]:
    return query_json(session, keys.param_all(vehicle), {"op": "list"})


@app.command("list")
def list_params(
    pattern: str = typer.Argument("*", help="Name filter, e.g. 'MC_*RATE*'"),
    module: str | None = typer.Option(None, "--module", "-m", help="Only this module"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """Parameters with their values, defaults, ranges and owning modules."""
    with connect(vehicle, endpoint) as node:
        answers = _all_params(node.session, node.vehicle)
    rows = []
    for answer in answers:
        if module is not None and answer["module"] != module:
            continue
        for p in answer.get("params", []):
            if fnmatch.fnmatchcase(p["name"], pattern):
                rows.append({**p, "module": answer["module"]})
    rows.sort(key=lambda r: (r["name"], r["module"]))
    if as_json:
        typer.echo(json.dumps(rows))
        return

    def mark(r: dict) -> str:
        return "*" if r["value"] != r["default"] else " "

    print_table(
        ("", "NAME", "VALUE", "DEFAULT", "MIN", "MAX", "UNIT", "MODULE"),
        [
            (mark(r), r["name"], r["value"], r["default"], _n(r["min"]), _n(r["max"]), r["unit"], r["module"])
            for r in rows
        ],
    )
    changed = sum(1 for r in rows if r["value"] != r["default"])
    typer.echo(f"{len(rows)} parameters, {changed} changed from default (*)")


def _n(value: object) -> str:
    return "" if value is None else f"{value:g}" if isinstance(value, float) else str(value)


@app.command()
def get(
    name: str,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """The value of one parameter (as each module that has it holds it)."""
    with connect(vehicle, endpoint) as node:
        answers = query_json(node.session, keys.param_all(node.vehicle), {"op": "get", "name": name})
    found = [a for a in answers if "error" not in a]
    if not found:
        fail(f"no running module has a parameter '{name}'")
    if as_json:
        typer.echo(json.dumps(found))
        return
    for a in sorted(found, key=lambda a: a["module"]):
        typer.echo(f"{a['name']} = {a['value']}  ({a['module']})")


@app.command("set")
def set_(
    name: str,
    value: str,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Change a parameter in every module that has it; the value is checked against type and range first."""
    with connect(vehicle, endpoint) as node:
        owners = [
            a["module"]
            for a in query_json(node.session, keys.param_all(node.vehicle), {"op": "get", "name": name})
            if "error" not in a
        ]
        if not owners:
            fail(f"no running module has a parameter '{name}'")
        results = []
        for owner in sorted(owners):
            results += query_json(
                node.session, keys.param_key(node.vehicle, owner), {"op": "set", "name": name, "value": value}
            )
    errors = [r for r in results if "error" in r]
    if errors:
        fail(errors[0]["error"])
    for r in results:
        typer.echo(f"{r['name']}: {r['old']} -> {r['new']}  ({r['module']})")
