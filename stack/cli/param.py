"""``stack param``: the parameters of a running stack, like PX4's ``param`` command and QGroundControl's
parameter page: list, get, set (in every module that reads it, or in none), save, load, reset."""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import typer

from stack.cli.common import (
    EndpointOption,
    JsonOption,
    VehicleOption,
    check_may_command,
    command_group,
    connect,
    fail,
    print_table,
)
from stack.params import catalogue, client, qgc_file
from stack.params.param import Param, ParamError, ParamValue

app = command_group(
    help="Parameters of the running modules: each is defined once (stack/params) and read by one or more modules; "
    "a set reaches every module that reads it, or none.",
    no_args_is_help=True,
)

SYSTEM_ID = "MAV_SYS_ID"


def _n(value: object) -> str:
    return "" if value is None else f"{value:g}" if isinstance(value, float) else str(value)


def _value(p: Param, value: object) -> str:
    """``2 (Return mode)`` for an enum or a bitmask, else the value as it is held."""
    meaning = p.meaning(value)
    return f"{value} ({meaning})" if meaning else str(value)


def _values(sp: client.StackParam) -> str:
    if sp.consistent:
        return _value(sp.param, sp.value)
    return ", ".join(f"{_value(sp.param, v)} [{m}]" for m, v in sp.values.items())


def _changed(sp: client.StackParam) -> bool:
    return any(v != sp.param.default for v in sp.values.values())


def _as_json(sp: client.StackParam) -> dict[str, object]:
    return {
        **sp.param.describe(),
        "value": sp.value,
        "meaning": sp.param.meaning(sp.value),
        "owners": list(sp.owners),
        "module_values": dict(sp.values),
    }


@app.command(
    "list",
    help="Parameters, one row each: the value (and what it means), the default, the range, the unit, the modules "
    "that read it and its description; * marks a value that is not the default.",
)
def list_params(
    pattern: str = typer.Argument("*", help="Name filter, case-insensitive, e.g. 'MC_*RATE*' or 'mc_*p'"),
    module: str | None = typer.Option(None, "--module", "-m", help="Only parameters this module reads"),
    changed: bool = typer.Option(False, "--changed", help="Only parameters not at their default"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    with connect(vehicle, endpoint) as node:
        params = client.list_params(node.session, node.vehicle)
    rows = [
        p
        for p in params
        if client.matches(pattern, p.name) and (module is None or module in p.owners) and (_changed(p) or not changed)
    ]
    if as_json:
        typer.echo(json.dumps([_as_json(p) for p in rows]))
        return
    print_table(
        ("", "NAME", "VALUE", "DEFAULT", "MIN", "MAX", "UNIT", "MODULES", "DESCRIPTION"),
        [
            (
                "*" if _changed(p) else " ",
                p.name,
                _values(p),
                _value(p.param, p.param.default),
                _n(p.param.min),
                _n(p.param.max),
                p.param.unit,
                ",".join(p.owners),
                p.param.doc,
            )
            for p in rows
        ],
    )
    typer.echo(f"{len(rows)} parameters, {sum(1 for p in rows if _changed(p))} changed from default (*)")


@app.command(help="One parameter: its value (and what it means), the modules that read it, and its definition.")
def get(
    name: str = typer.Argument(..., help="The parameter (any case)"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    with connect(vehicle, endpoint) as node:
        try:
            p = client.get_param(node.session, node.vehicle, name)
        except ParamError as e:
            fail(str(e))
    if as_json:
        typer.echo(json.dumps(_as_json(p)))
        return
    d = p.param
    unit = f" {d.unit}" if d.unit else ""
    typer.echo(f"{p.name} = {_values(p)}{unit}  ({', '.join(p.owners)})")
    if d.doc:
        typer.echo(f"  {d.doc}")
    facts = [f"default {_value(d, d.default)}", f"type {d.type.__name__}"]
    if d.min is not None or d.max is not None:
        facts.append(f"range {_n(d.min) or '-inf'} … {_n(d.max) or 'inf'}")
    if d.values:
        facts.append("values " + ", ".join(f"{v} {m}" for v, m in d.values.items()))
    if d.bits:
        facts.append("bits " + ", ".join(f"{b} {m}" for b, m in d.bits.items()))
    typer.echo("  " + "; ".join(facts))


def _system_id(listed: list[client.StackParam]) -> int:
    """The vehicle's MAVLink system id: its modules' MAV_SYS_ID, or the parameter's default if none reads it."""
    found = next((p for p in listed if p.name == SYSTEM_ID), None)
    return int(found.value if found is not None else catalogue.get(SYSTEM_ID).default)


def _report_set(result: client.SetResult, p: Param) -> None:
    by_old: dict[ParamValue, list[str]] = defaultdict(list)
    for owner, old in result.old.items():
        by_old[old].append(owner)
    for old, owners in by_old.items():
        typer.echo(f"{result.name}: {_value(p, old)} -> {_value(p, result.new)}  ({', '.join(owners)})")


@app.command(
    "set",
    context_settings={"ignore_unknown_options": True},
    help="Change a parameter in every module that reads it, or in none: each of them checks the value against the "
    "parameter's type, range and values first, and a refusal changes nothing anywhere.",
)
def set_(
    name: str = typer.Argument(..., help="The parameter (any case)"),
    value: str = typer.Argument(..., help="The new value; a negative number is a value, not an option"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    check_may_command(endpoint)
    with connect(vehicle, endpoint) as node:
        try:
            p = client.get_param(node.session, node.vehicle, name)
            result = client.set_in_owners(node.session, node.vehicle, p, value)
        except ParamError as e:
            fail(str(e))
    _report_set(result, p.param)


@app.command(
    help="Set a parameter (or --all) back to its default: the default of its definition in stack/params, which is "
    "PX4's firmware default as PX4's `param reset` restores it, not the value the launch profile's params table or "
    "its airframe gave. --all therefore also resets the airframe's CA_* geometry: use it on the ground.",
)
def reset(
    name: str | None = typer.Argument(None, help="The parameter (any case)"),
    all_: bool = typer.Option(False, "--all", help="Every parameter not at its default"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    if (name is None) == (not all_):
        fail("give a parameter name or --all (not both)", code=2)
    with connect(vehicle, endpoint) as node:
        if not all_:
            try:
                p = client.get_param(node.session, node.vehicle, str(name))
                result = client.set_in_owners(node.session, node.vehicle, p, p.param.default)
            except ParamError as e:
                fail(str(e))
            _report_set(result, p.param)
            return
        params = {p.name: p.param for p in client.list_params(node.session, node.vehicle)}
        done, refused = client.reset_all(node.session, node.vehicle)
    for result in done:
        _report_set(result, params[result.name])
    for e in refused:
        typer.echo(f"error: {e}", err=True)
    typer.echo(f"{len(done)} parameters reset to their defaults")
    if refused:
        raise typer.Exit(1)


@app.command(
    help="Save every parameter's value to a QGroundControl .params file: tab-separated vehicle id, component id, "
    "name, value and MAV_PARAM_TYPE (6 INT32, 9 REAL32), after # header lines.",
)
def save(
    file: Path = typer.Argument(..., help="The .params file to write (QGroundControl's format)"),
    system_id: int | None = typer.Option(
        None, "--system-id", min=1, max=255, help="Vehicle-Id column (default: the vehicle's MAV_SYS_ID)"
    ),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    with connect(vehicle, endpoint) as node:
        params = client.list_params(node.session, node.vehicle)
        name = node.vehicle
    if system_id is None:
        system_id = _system_id(params)
    for p in params:
        if not p.consistent:
            typer.echo(f"warning: {p.name} differs between modules ({_values(p)}); saving {p.value}", err=True)
    text = qgc_file.format_file(((p.name, p.value, p.param.mav_type) for p in params), name, system_id)
    try:
        file.write_text(text)
    except OSError as e:
        fail(f"cannot write {file}: {e.strerror}")
    typer.echo(f"saved {len(params)} parameters to {file}")


@app.command(
    help="Set the parameters of a QGroundControl .params file, each in every module that reads it or in none. "
    "Lines that are not parameters, unknown names and refused values are reported and the other lines still "
    "applied; the exit code is then 1.",
)
def load(
    file: Path = typer.Argument(..., help="A QGroundControl .params file"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    try:
        entries, problems = qgc_file.parse_file(file.read_text())
    except (OSError, UnicodeDecodeError) as e:
        fail(f"cannot read {file}: {getattr(e, 'strerror', None) or e}")
    check_may_command(endpoint)
    with connect(vehicle, endpoint) as node:
        listed = client.list_params(node.session, node.vehicle)
        if (why := qgc_file.other_vehicle(entries, _system_id(listed))) is not None:
            fail(f"{file}: {why}; nothing set (save the file from this vehicle, or change its Vehicle-Id column)")
        params = {p.name: p.param for p in listed}
        report = client.set_many(node.session, node.vehicle, ((e.name, e.value, e.mav_type) for e in entries))
    for result in report.changed:
        _report_set(result, params[result.name])
    for message in [*problems, *report.unknown, *report.refused]:
        typer.echo(f"error: {message}", err=True)
    typer.echo(
        f"{file}: {len(report.changed)} changed, {len(report.unchanged)} unchanged, {len(report.refused)} refused, "
        f"{len(report.unknown)} unknown, {len(problems)} lines not parameters"
    )
    if problems or report.unknown or report.refused:
        raise typer.Exit(1)
