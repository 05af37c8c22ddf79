"""``stack fly SCENARIO``: bring a stack up, fly a scripted scenario against it, write a JSON report."""

from __future__ import annotations

import json
import os
from pathlib import Path

import typer

from stack.cli.common import (
    InsecureOption,
    KeystoreOption,
    TransportOption,
    check_exposure,
    choose_transport,
    fail,
    number,
    output_file,
    print_table,
)
from stack.cli.observers import add_observers
from stack.scenario.catalogue import scenarios, unknown_scenario
from stack.scenario.flight import WIND_SPEED, prepare_flight
from stack.supervisor import state as run_state
from stack.supervisor.profile import DEFAULT_PROFILE, ProfileError, load_profile


def fly(
    scenario: str = typer.Argument("", help="Scenario name (see --list)"),
    profile: str | None = typer.Option(
        None,
        "--profile",
        "-p",
        help=f"Launch profile: a name in launch/ or a path (default: the scenario's own, or {DEFAULT_PROFILE})",
    ),
    seed: int | None = typer.Option(None, "--seed", "-s", help="Override the profile's seed"),
    report: Path | None = typer.Option(
        None, "--report", "-r", callback=output_file, help="Where to write the JSON report"
    ),
    list_: bool = typer.Option(False, "--list", help="List the scenarios and exit"),
    log_level: str = typer.Option("INFO", help="Log level of the modules"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only the scenario's progress and the result"),
    plot_: bool = typer.Option(False, "--plot", help="Live Rerun plots of the flight"),
    web: bool = typer.Option(False, "--web", help="Serve the Rerun web viewer on 127.0.0.1 and print its URL"),
    save: str | None = typer.Option(
        None, "--save", callback=output_file, help="Write the flight's plots to this .rrd file"
    ),
    record: Path | None = typer.Option(
        None, "--record", callback=output_file, help="Record every topic to this MCAP file"
    ),
    wind: bool = typer.Option(
        False, "--wind", help=f"Fly in {WIND_SPEED:g} m/s wind with gusts; the limits are doubled"
    ),
    wind_speed: float | None = typer.Option(
        None, "--wind-speed", callback=number(0, 30), help="Fly in this wind (m/s) instead of --wind's; implies --wind"
    ),
    transport: str | None = TransportOption,
    host: str | None = typer.Option(
        None,
        "--host",
        help="Of a profile spread over machines ([hosts]): the host this machine is, where the scenario runs "
        "(the others run `stack up PROFILE --host NAME`)",
    ),
    vehicles: int = typer.Option(
        1, "--vehicles", min=1, help="Fly a swarm scenario with this many copies of the profile's vehicle (v1 leads)"
    ),
    insecure: bool = InsecureOption,
    keystore: Path | None = KeystoreOption,
    here: str = typer.Option(
        "", "--here", help="Of a swarm spread over machines: the vehicles this one flies (v1,v2); see --listen, --join"
    ),
    listen: list[str] = typer.Option(
        [], "--listen", help="With --here: where the other machines reach this one's share (e.g. tcp/10.0.0.1:7447)"
    ),
    join: list[str] = typer.Option([], "--join", help="With --here: another machine's --listen endpoint to join"),
    swarm_vehicle: int = typer.Option(0, "--swarm-vehicle", hidden=True, help="Fly vehicle I of a swarm"),
    swarm_size: int = typer.Option(0, "--swarm-size", hidden=True, help="Of a swarm of N vehicles"),
    swarm_join: str = typer.Option("", "--swarm-join", hidden=True, help="Joining the first vehicle's bus there"),
    swarm_world: str = typer.Option("", "--swarm-world", hidden=True, help="On the world clock in this file"),
    swarm_result: str = typer.Option("", "--swarm-result", hidden=True, help="Where the scenario writes its result"),
) -> None:
    """Fly a scripted scenario (in lockstep, deterministic for a seed) and report how well the stack flew.

    Each flight is a stack of its own (bus, ports, run directory, state) named <vehicle>-fly-<pid>;
    it runs beside `stack up` and other flights, and other terminals reach it with --vehicle <name>.
    """
    known = scenarios()
    if list_ or not scenario:
        width = max(len(name) for name in known)
        for s in known.values():
            typer.echo(f"{s.name:{width}s}  {s.description}")
        raise typer.Exit(0)
    if scenario not in known:
        fail(unknown_scenario(scenario), code=2)
    swarm = known[scenario].swarm
    if swarm is not None and not swarm_vehicle and vehicles < swarm.min_vehicles:
        fail(f"scenario {scenario} flies a swarm: give --vehicles N, N at least {swarm.min_vehicles}", code=2)
    if swarm is None and vehicles > 1:
        swarms = ", ".join(sorted(n for n, s in known.items() if s.swarm is not None))
        fail(f"scenario {scenario} flies one vehicle; the swarm scenarios: {swarms}", code=2)
    try:
        flags = {"plot": plot_ or web, "record": record is not None}
        prof = load_profile(profile or known[scenario].profile or DEFAULT_PROFILE, flags=flags)
        prof.check_host(host)
    except ProfileError as e:
        fail(str(e), code=2)
    check_exposure(prof, host, insecure, keystore)
    choose_transport(prof, transport)
    if seed is not None:
        prof.seed = seed
    spread_options = [o for o, v in (("--here", here), ("--listen", listen), ("--join", join)) if v]
    if spread_options and (vehicles < 2 or not here):
        fail(f"{', '.join(spread_options)}: a share of a swarm flight: give --vehicles N and --here", code=2)
    if here and not (listen or join):
        fail(
            "--here: the other machines' shares reach this one with --listen ENDPOINT, or it joins one with --join",
            code=2,
        )
    from stack.security.exposure import exposure_problem

    remedy = "Listen on a tls/ endpoint, as a host of a keystore (`stack --keystore DIR --identity NAME fly ...`)"
    if problem := exposure_problem("this machine's share of the swarm", listen, insecure, remedy):
        fail(problem, code=2)
    if vehicles > 1:
        given = [o for o, v in (("--plot", plot_), ("--web", web), ("--save", save), ("--record", record)) if v]
        given += ["--host"] if host is not None else []
        if given:
            fail(f"--vehicles flies a swarm of whole vehicles: not with {', '.join(given)}", code=2)
        from stack.cli.swarm_fly import Spread, fly_swarm  # what starts the vehicles, only when it will

        spread = None
        if here:
            from stack.cli.swarm_hub import hub_security
            from stack.security.keystore import KeystoreError

            try:
                tls, access = hub_security(listen, join)
            except KeystoreError as e:
                fail(str(e), code=2)
            vehicles_here = [n.strip() for n in here.split(",") if n.strip()]
            spread = Spread(vehicles_here, listen, join, tls, access, prof.count_denials)

        wind_args = ["--wind-speed", str(wind_speed)] if wind_speed is not None else ["--wind"] if wind else []
        args = ["fly", scenario, *(("--profile", profile) if profile else ()), "--seed", str(prof.seed)]
        args += ["--log-level", log_level, *(("--quiet",) if quiet else ()), *wind_args]
        args += ("--lockstep-transport", transport) if transport else ()
        args += ("--insecure",) if insecure else ()
        raise typer.Exit(fly_swarm(prof, known[scenario], vehicles, args, report, spread))
    world: dict[str, object] = {}
    role = ""
    if swarm_vehicle:
        from stack.cli.swarm_launch import vehicle_of_swarm

        prof, names, world = vehicle_of_swarm(prof, swarm_vehicle, swarm_size, swarm_join, swarm_world)
        role = json.dumps({"slot": swarm_vehicle, "vehicles": names, "spacing_m": prof.swarm_spacing_m})
    prof.port = 0  # the flight's own router, on a free port
    # A flight is a stack of its own beside others: the links to the world outside (ground-station ports)
    # belong to `stack up`, and a scripted flight needs none.
    prof.modules = [m for m in prof.modules if not m.cls.OUTSIDE_LOCKSTEP]
    name = run_state.flight_name(prof.vehicle, os.getpid())
    run_dir = run_state.new_run_dir(scenario, name)
    result_path = Path(swarm_result) if swarm_result else run_dir / "scenario_result.json"
    try:
        wind = wind or wind_speed is not None
        speed = WIND_SPEED if wind_speed is None else wind_speed
        prepare_flight(prof, scenario, result_path, wind, speed, host or "", role)
    except ValueError as e:
        fail(f"scenario {scenario}: {e}", code=2)
    add_observers(prof, plot=plot_, web=web, save=save, record=record, own_ports=True, host=host or "")
    shown = ("scenario", "rerun_bridge") if web else ("scenario",)  # the web viewer's URL, even with --quiet
    from stack.supervisor.supervisor import Supervisor, UpOptions  # what starts processes, only when it will

    options = UpOptions(log_level=log_level, echo_logs=not quiet, echo_only=shown, kind=run_state.FLY, **world)
    typer.echo(f"[stack] flight '{name}' (another terminal addresses it with --vehicle {name})")
    code = Supervisor(prof, options, run_dir, host).run()
    if not result_path.exists():
        fail(f"the scenario produced no result (supervisor exit code {code}); see the logs in {run_dir}")
    result = json.loads(result_path.read_text())
    full = {
        "scenario": scenario,
        "profile": prof.name,
        "seed": prof.seed,
        "wind": wind,
        "wind_speed_m_s": (WIND_SPEED if wind_speed is None else wind_speed) if wind else 0.0,
        "passed": result["passed"],
        "sim_time_s": result["sim_time_s"],
        "wall_time_s": result["wall_time_s"],
        "realtime_factor": result["realtime_factor"],
        "metrics": result["metrics"],
        "checks": result["checks"],
        "error": result["error"],
        "run_dir": str(run_dir),
        "recording": str(record.resolve()) if record is not None else None,
    }
    out = report or run_dir / "report.json"
    out.write_text(json.dumps(full, indent=2))
    print_summary(full, out)
    raise typer.Exit(0 if full["passed"] else 1)


def print_summary(report: dict, path: Path) -> None:
    status = "PASSED" if report["passed"] else "FAILED"
    windy = f", in {report['wind_speed_m_s']:g} m/s wind" if report["wind"] else ""
    typer.echo(
        f"\n{report['scenario']} on {report['profile']} (seed {report['seed']}{windy}): {status} — "
        f"{report['sim_time_s']:.1f} s simulated in {report['wall_time_s']:.1f} s "
        f"(real-time factor {report['realtime_factor']:.1f})"
    )
    if report["error"]:
        typer.echo(f"error: {report['error']}")
    rows = [(c["name"], _fmt(c["value"]), _fmt(c["limit"]), "ok" if c["passed"] else "FAIL") for c in report["checks"]]
    print_table(("CHECK", "VALUE", "LIMIT", ""), rows)
    others = {k: v for k, v in report["metrics"].items() if k not in {c["name"] for c in report["checks"]}}
    for k, v in others.items():
        typer.echo(f"{k}: {_fmt(v)}")
    typer.echo(f"report: {path}")


def _fmt(value: object) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
