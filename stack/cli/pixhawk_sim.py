"""``stack pixhawk-sim``: a simulated PX4 Pixhawk on a MAVLink link, for flying the stack without hardware."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from stack.cli.common import fail, number, output_file
from stack.mavlink.endpoint import DEFAULT_BAUD


def _param_overrides(items: list[str]) -> dict[str, str]:
    overrides = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            fail(f"--param expects NAME=VALUE, got {item!r}", code=2)
        overrides[name.strip()] = value.strip()
    return overrides


def pixhawk_sim(
    link: str | None = typer.Option(
        None,
        "--link",
        help="UDP endpoint: udpout:HOST:PORT (send to the companion) or udpin:HOST:PORT (listen); "
        "default udpout:127.0.0.1:14540 (PX4 SITL's offboard port) unless --pty-link is given",
    ),
    pty_link: Path | None = typer.Option(
        None,
        "--pty-link",
        help="Serve a UART (--baud) on a pseudo-terminal and symlink this path to it "
        "(the stack opens serial:PATH:BAUD)",
    ),
    baud: int = typer.Option(DEFAULT_BAUD, "--baud", min=1, help="UART baud rate of the pty link (10 bits per byte)"),
    vehicle: str = typer.Option("sih_quad", "--vehicle", help="Vehicle model (stack/airframe/vehicles) or a path"),
    system_id: int = typer.Option(1, "--sysid", min=1, max=255, help="MAVLink system id (PX4 MAV_SYS_ID)"),
    component_id: int = typer.Option(1, "--compid", min=1, max=255, help="MAVLink component id (autopilot: 1)"),
    param: list[str] = typer.Option([], "--param", help="PX4 parameter NAME=VALUE (repeatable)"),
    params_file: Path | None = typer.Option(
        None,
        "--params",
        help="TOML file whose params table sets parameters (a launch profile qualifies; the "
        "names the Pixhawk does not use are listed and ignored)",
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the sensor noise and of the link faults"),
    drop: float = typer.Option(0.0, "--drop", help="Share of packets dropped in each direction"),
    corrupt: float = typer.Option(0.0, "--corrupt", help="Probability per byte of a flipped bit"),
    latency_ms: float = typer.Option(0.0, "--latency-ms", help="Added one-way latency"),
    jitter_ms: float = typer.Option(0.0, "--jitter-ms", help="Latency varies by ± this much (uniform)"),
    cut_at: float | None = typer.Option(
        None, "--cut-at", callback=number(0), help="Cut the link this many seconds after start"
    ),
    cut_for: float = typer.Option(2.0, "--cut-for", callback=number(0), help="Length of the --cut-at cut [s]"),
    control_port: int | None = typer.Option(
        None,
        "--control-port",
        min=0,
        max=65535,
        help="Serve the JSON control channel on this 127.0.0.1 UDP port (0: any free port)",
    ),
    duration: float | None = typer.Option(None, "--duration", callback=number(0), help="Stop after this many seconds"),
    stats_period: float = typer.Option(
        0.0, "--stats-period", callback=number(0), help="Print timing and link stats to stderr every N s"
    ),
    report: Path | None = typer.Option(
        None, "--report", callback=output_file, help="Write the final report (JSON) here"
    ),
) -> None:
    """A simulated PX4 Pixhawk: the stack's simulator with PX4's rate controller and allocator, paced to the wall
    clock behind a MAVLink endpoint that behaves as PX4 firmware does (streams, commands, Offboard, failsafes).
    It talks MAVLink only; it never joins the stack's bus."""
    from stack.airframe.model import load_vehicle
    from stack.params.param import ParamError
    from stack.pixhawk_sim.faults import FaultSettings
    from stack.pixhawk_sim.params import parameter_values, read_params_file
    from stack.pixhawk_sim.runner import RunOptions, run

    if link is not None and pty_link is not None:
        fail("give either --link or --pty-link, not both", code=2)
    if link is None and pty_link is None:
        link = "udpout:127.0.0.1:14540"
    try:
        model = load_vehicle(vehicle)
    except (OSError, ValueError) as e:
        fail(f"vehicle {vehicle!r}: {e}", code=2)
    overrides: dict[str, object] = {}
    if params_file is not None:
        try:
            used, ignored = read_params_file(params_file)
        except (OSError, ValueError) as e:
            fail(f"--params {params_file}: {e}", code=2)
        overrides.update(used)
        if ignored:
            typer.echo(f"[pixhawk-sim] ignoring parameters it does not use: {', '.join(ignored)}", err=True)
    overrides.update(_param_overrides(param))
    try:
        values = parameter_values(model, overrides)
    except ParamError as e:
        fail(str(e), code=2)
    faults = FaultSettings(drop=drop, corrupt=corrupt, latency_ms=latency_ms, jitter_ms=jitter_ms)
    try:
        faults.check()
        options = RunOptions(
            vehicle=model,
            params=values,
            udp=link,
            pty_link=pty_link,
            baud=baud,
            system_id=system_id,
            component_id=component_id,
            seed=seed,
            faults=faults,
            cut_at_s=cut_at,
            cut_for_s=cut_for,
            control_port=control_port,
            duration_s=duration,
            stats_period_s=stats_period,
            report=report,
        )
        result = run(options)
    except (OSError, ValueError) as e:
        fail(str(e))
    typer.echo(json.dumps({"stats": result["stats"], "link": result["link"], "faults": result["faults"]}))
