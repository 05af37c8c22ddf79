"""The ``stack`` command."""

from __future__ import annotations

import json
import os
import re
import sys
import time
from decimal import Decimal
from pathlib import Path
from typing import Any

import typer

import stack
from stack.bus.supervisors import vehicle_status
from stack.cli import (
    cmd,
    down,
    fly,
    keys,
    log,
    mavlink,
    param,
    pixhawk_sim,
    plot,
    router,
    teleop,
    topic,
    vehicle_summary,
    vehicles,
)
from stack.cli.common import (
    IDENTITY_ENV,
    KEYSTORE_ENV,
    EndpointOption,
    InsecureOption,
    JsonOption,
    KeystoreOption,
    TransportOption,
    VehicleOption,
    check_exposure,
    choose_transport,
    command_group,
    connect,
    connect_all,
    fail,
    name_value_placeholders,
    number,
    output_file,
    print_table,
    to_jsonable,
)
from stack.cli.observers import add_observers
from stack.runtime.pacing import SPEED_ENV, describe_speed, parse_speed
from stack.supervisor import state as run_state
from stack.supervisor.profile import DEFAULT_PROFILE, Profile, ProfileError, load_profile

app = command_group(
    help="stack: a PX4-shaped multicopter autopilot, one process per module, uORB topics over Zenoh.",
    no_args_is_help=True,
    add_completion=False,
    context_settings={"help_option_names": ["-h", "--help"]},  # inherited by every subcommand
)
app.add_typer(topic.app, name="topic")
app.add_typer(param.app, name="param")
app.add_typer(log.app, name="log")
app.add_typer(cmd.app, name="cmd")
app.add_typer(mavlink.app, name="mavlink")
app.add_typer(keys.app, name="keys")
app.command("fly")(fly.fly)
app.command("plot")(plot.plot)
app.command("replay")(log.replay)
app.command("pixhawk-sim")(pixhawk_sim.pixhawk_sim)
app.command("teleop")(teleop.teleop)
app.command("router")(router.router)
app.command("down")(down.down)
app.command("vehicles")(vehicles.vehicles)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"stack {stack.__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_print_version, is_eager=True, help="Print the version and exit"
    ),
    keystore: Path | None = typer.Option(
        None, "--keystore", envvar=KEYSTORE_ENV, help="The keystore of the identity a tool presents on a tls/ endpoint"
    ),
    identity: str | None = typer.Option(
        None, "--identity", envvar=IDENTITY_ENV, help="Who a tool is on a tls/ endpoint (stack keys issue)"
    ),
) -> None:
    # read where a tool opens its bus (stack.cli.common.endpoint_bus), as the variables would be
    if keystore is not None:
        os.environ[KEYSTORE_ENV] = str(keystore)
    if identity is not None:
        os.environ[IDENTITY_ENV] = identity


@app.command()
def up(
    profile: str = typer.Argument(DEFAULT_PROFILE, help="Launch profile: a name in launch/ or a path"),
    duration: float | None = typer.Option(
        None, "--duration", "-d", callback=number(0), help="Stop after this many seconds"
    ),
    speed: str | None = typer.Option(
        None,
        "--speed",
        help="Lockstep pace: simulated seconds per wall-clock second (default 1: real speed; 2: twice as fast), "
        f"or max: as fast as the machine goes (default: ${SPEED_ENV}, else 1)",
    ),
    realtime: bool = typer.Option(
        False, "--realtime", help="No lockstep: every module on the wall clock (as on a real vehicle)"
    ),
    log_level: str = typer.Option("INFO", help="Log level of the modules"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Do not echo module logs (they are still written)"),
    plot_: bool = typer.Option(False, "--plot", help="Live Rerun plots (a viewer where a display exists)"),
    web: bool = typer.Option(False, "--web", help="Serve the Rerun web viewer on 127.0.0.1 and print its URL"),
    save: str | None = typer.Option(
        None, "--save", callback=output_file, help="Write the live plots to this .rrd file"
    ),
    record: Path | None = typer.Option(
        None, "--record", callback=output_file, help="Record every topic to this MCAP file"
    ),
    transport: str | None = TransportOption,
    device: str | None = typer.Option(
        None,
        "--device",
        help="MAVLink endpoint of the Pixhawk (profiles with the pixhawk module), e.g. "
        "serial:/dev/ttyACM0:921600 or udp:0.0.0.0:14540",
    ),
    host: str | None = typer.Option(
        None, "--host", help="The host of a profile spread over machines ([hosts]) whose share this machine runs"
    ),
    insecure: bool = InsecureOption,
    keystore: Path | None = KeystoreOption,
    vehicles: int = typer.Option(
        1, "--vehicles", min=1, help="A swarm: this many copies of the profile's vehicle on one bus (v1, v2...)"
    ),
    swarm_vehicle: int = typer.Option(0, "--swarm-vehicle", hidden=True, help="Run vehicle I of a swarm"),
    swarm_size: int = typer.Option(0, "--swarm-size", hidden=True, help="Of a swarm of N vehicles"),
    swarm_join: str = typer.Option("", "--swarm-join", hidden=True, help="Joining the first vehicle's bus there"),
    swarm_world: str = typer.Option("", "--swarm-world", hidden=True, help="On the world clock in this file"),
) -> None:
    """Start a stack from a launch profile and supervise it until Ctrl-C, SIGTERM or --duration."""
    try:
        prof = load_profile(profile, flags={"realtime": realtime, "plot": plot_ or web, "record": record is not None})
        prof.check_host(host)
    except ProfileError as e:
        fail(str(e), code=2)
    check_exposure(prof, host, insecure, keystore)
    if vehicles > 1:
        given = [o for o, v in (("--plot", plot_), ("--web", web), ("--save", save), ("--record", record)) if v]
        given += [o for o, v in (("--device", device), ("--host", host)) if v is not None]
        if given:
            fail(f"--vehicles starts a swarm of whole vehicles on this machine: not with {', '.join(given)}", code=2)
        from stack.cli.swarm_launch import check_swarm, run_swarm  # what starts the vehicles, only when it will

        try:
            names = check_swarm(prof, vehicles)
        except ValueError as e:
            fail(str(e), code=2)
        running = [n for n in names if run_state.addressed_stacks(n)]
        if running:
            fail(f"a stack for vehicle '{running[0]}' is already running; `stack down` first")
        up_args = ["up", profile, "--log-level", log_level, *(("--duration", str(duration)) if duration else ())]
        up_args += [*(("--speed", speed) if speed else ()), *(("--realtime",) if realtime else ())]
        up_args += [*(("--quiet",) if quiet else ()), *(("--lockstep-transport", transport) if transport else ())]
        raise typer.Exit(run_swarm(names, up_args, run_state.new_run_dir(prof.name, "swarm")))
    world: dict[str, Any] = {}
    if swarm_vehicle:
        from stack.cli.swarm_launch import vehicle_of_swarm

        prof, _, world = vehicle_of_swarm(prof, swarm_vehicle, swarm_size, swarm_join, swarm_world)
    choose_transport(prof, transport)
    pace = _speed(prof, speed, realtime)
    extra_args = _device_args(prof, device) if device is not None else {}
    add_observers(prof, plot=plot_, web=web, save=save, record=record, host=host or "")
    running = run_state.addressed_stacks(prof.vehicle)
    if running:
        fail(f"a stack for vehicle '{prof.vehicle}' is already running (pid {running[0]['pid']}); `stack down` first")
    run_dir = run_state.new_run_dir(prof.name, prof.vehicle)
    # The web viewer's URL is shown even with --quiet: the bridge's few lines are echoed.
    shown = ("rerun_bridge",) if web else ()
    from stack.supervisor.supervisor import Supervisor, UpOptions  # what starts processes, only when it will

    options = UpOptions(
        duration=duration,
        log_level=log_level,
        echo_logs=not quiet,
        echo_only=shown,
        extra_args=extra_args,
        speed=pace,
        **world,
    )
    supervisor = Supervisor(prof, options, run_dir, host)
    if record is not None:
        typer.echo(f"[stack] recording to {record.resolve()}")
    raise typer.Exit(supervisor.run())


def _speed(prof: Profile, text: str | None, realtime: bool) -> float:
    """``--speed``: the lockstep's pace, refused where there is no lockstep to pace; without it, SPEED_ENV's
    (as PX4 SITL reads PX4_SIM_SPEED_FACTOR), else real speed."""
    if text is None:
        default = os.environ.get(SPEED_ENV, "").strip()
        try:
            return parse_speed(default) if default else 1.0
        except ValueError as e:
            fail(f"{SPEED_ENV}: {e}", code=2)
    if realtime:
        fail("--speed paces the lockstep and --realtime runs without one: choose one of them", code=2)
    if not prof.lockstep:
        fail(f"--speed: profile {prof.name} runs without lockstep, on the wall clock: there is nothing to pace", code=2)
    try:
        return parse_speed(text)
    except ValueError as e:
        fail(f"--speed: {e}", code=2)


def _device_args(prof: Profile, device: str) -> dict[str, dict[str, object]]:
    """``--device``: the ``device`` argument of the profile's pixhawk module(s), checked before anything starts."""
    from stack.mavlink.endpoint import parse_endpoint
    from stack.pixhawk.module import PixhawkAdapterModule

    try:
        parse_endpoint(device)
    except ValueError as e:
        fail(f"--device: {e}", code=2)
    names = [m.name for m in prof.modules if issubclass(m.cls, PixhawkAdapterModule)]
    if not names:
        fail(f"--device: profile {prof.name} has no pixhawk module (try: stack up pixhawk --device ...)", code=2)
    return {name: {"device": device} for name in names}


DROP_COUNTERS = {
    "decode_errors": "malformed",
    "schema_errors": "of another schema",
    "foreign": "of another lockstep run",
    "unauthorized": "from a publisher outside the vehicle",
    "invalid": "holding NaN or infinity where not allowed",
    "rejected": "refused by the module",
}
"""A module's counters of messages it did not act on, in the ERR column, and what each counts."""


@app.command()
def status(
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    every: bool = typer.Option(False, "--all", help="Every vehicle on the bus, one after the other (JSON: a list)"),
    as_json: bool = JsonOption,
) -> None:
    """The vehicle (mode, armed, failsafe, position, battery, as PX4's `commander status`), then each
    module's state, pid, CPU, memory, restarts, trigger rate and counters."""
    if every:
        if vehicle is not None:
            fail("--all addresses every vehicle: give it or --vehicle, not both", code=2)
        with connect_all(endpoint) as nodes:
            reports = {n.vehicle: r for n in nodes if (r := vehicle_status(n.session, n.vehicle)) is not None}
            vehicle_summary.add_summaries(reports, nodes)
        if as_json:
            typer.echo(json.dumps(to_jsonable(list(reports.values()))))
            return
        for i, report in enumerate(reports.values()):
            if i:
                typer.echo("")
            _print_status(report)
        return
    with connect(vehicle, endpoint) as node:
        report = vehicle_status(node.session, node.vehicle)
        if report is None:
            fail("the supervisor did not answer")
        vehicle_summary.add_summaries({node.vehicle: report}, [node])
    if as_json:
        typer.echo(json.dumps(to_jsonable(report)))
        return
    _print_status(report)


def _print_status(report: dict[str, Any]) -> None:
    mode = "lockstep" if report["lockstep"] else "real time"
    if report["lockstep"] and "speed" in report:
        mode += f", {describe_speed(report['speed'])}"
    typer.echo(f"vehicle '{report['vehicle']}', profile {report['profile']} ({mode})")
    if "vehicle_summary" in report:
        for line in vehicle_summary.lines(report["vehicle_summary"]):
            typer.echo(line)
    # Modules sharing a process (a profile's `process = "NAME"`) show it; their CPU% and MEM are the process's.
    shared = any(m.get("process", m["module"]) != m["module"] for m in report["modules"])
    spread = bool(report.get("placement"))  # a vehicle over several hosts: each module's host
    rows = []
    for m in report["modules"]:
        rows.append(
            (
                m["module"],
                *((m.get("host", ""),) if spread else ()),
                *((m.get("process", m["module"]),) if shared else ()),
                m["state"],
                m["pid"] or "-",
                f"{m.get('cpu_percent', 0.0):.1f}",
                f"{m.get('rss_bytes', 0) / 2**20:.0f}M",
                m["restarts"],
                f"{m.get('trigger_rate_hz', 0.0):.1f}",
                m.get("runs", 0),
                m.get("msgs_in", 0),
                m.get("msgs_out", 0),
                sum(m.get(k, 0) for k in DROP_COUNTERS),
                f"{m.get('loop_avg_us', 0.0):.0f}/{m.get('loop_max_us', 0.0):.0f}",
            )
        )
    columns = ("STATE", "PID", "CPU%", "MEM", "RESTARTS", "RATE", "RUNS", "IN", "OUT", "ERR", "LOOP us")
    print_table(("MODULE", *(("HOST",) if spread else ()), *(("PROCESS",) if shared else ()), *columns), rows)
    for host in report.get("silent_hosts", []):
        modules = ", ".join(report["placement"][host])
        typer.echo(f"host {host}: its supervisor does not answer (lost, or not started): {modules}")
    for host, seen_by in report.get("lost_hosts", {}).items():
        modules = ", ".join(report["placement"].get(host, [])) or "no modules"
        typer.echo(f"host {host}: lost to host {', '.join(seen_by)} (no beat within the lease): {modules}")
    for host, denials in report.get("denied", {}).items():
        total = sum(d["count"] for d in denials)
        typer.echo(f"host {host}: its router denied {total} message{'s' if total != 1 else ''}:")
        for d in denials:
            typer.echo(f"  {d['count']} × {d['who']}: {d['action']} ({d['flow']}) on {d['key']}")
    for m in report["modules"]:
        drops = [f"{DROP_COUNTERS[k]} {m[k]}" for k in DROP_COUNTERS if m.get(k)]
        if drops:
            typer.echo(f"{m['module']}: refused or dropped: {', '.join(drops)}")
    for m in report["modules"]:
        if m.get("extra"):  # a module's own figures (e.g. pixhawk: its MAVLink link and time sync)
            figures = (f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in m["extra"].items())
            typer.echo(f"{m['module']}: " + ", ".join(figures))
    sim_times = [m.get("sim_time_us", 0) for m in report["modules"]]
    if report["lockstep"] and any(sim_times):
        typer.echo(f"simulated time {max(sim_times) / 1e6:.3f} s at {time.strftime('%H:%M:%S')}")


def cli() -> Any:
    """The ``stack`` command as Click runs it, each value's placeholder its name."""
    command = typer.main.get_command(app)
    name_value_placeholders(command)
    return command


_EXPONENT_NUMBER = re.compile(r"-(\d+\.?\d*|\.\d+)[eE][+-]?\d+")


def numbers_as_values(args: list[str]) -> list[str]:
    """A negative number in exponent form (``-2.1e-05``, as ``str()`` writes a small float) written out in full:
    click would read its letters as short options (``-e`` is ``--endpoint``); a plain negative number it leaves a
    value."""
    return [format(Decimal(a), "f") if _EXPONENT_NUMBER.fullmatch(a) else a for a in args]


def main() -> None:
    cli()(args=numbers_as_values(sys.argv[1:]))
