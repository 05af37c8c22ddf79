"""``stack mavlink``: tools for a MAVLink autopilot link."""

from __future__ import annotations

import json

import typer

from stack.cli.common import JsonOption, command_group, fail, number

app = command_group(help="Tools for a MAVLink autopilot (a Pixhawk, a simulated one, any MAVLink system).")


@app.command()
def inspect(
    endpoint: str = typer.Argument(
        ..., help="serial:/dev/ttyACM0:921600, udp:HOST:PORT (listen), udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT"
    ),
    seconds: float = typer.Option(5.0, "--seconds", "-s", callback=number(0.5), help="How long to listen"),
    as_json: bool = JsonOption,
) -> None:
    """Connect to an autopilot and print its ids, type, firmware, armed state and mode, message rates and link
    errors. Exits non-zero if no autopilot heartbeat arrives."""
    from stack.mavlink.inspect import NoHeartbeat, format_summary, inspect_endpoint  # pymavlink, only when asked

    try:
        summary = inspect_endpoint(endpoint, seconds)
    except ValueError as e:
        fail(str(e), code=2)
    except NoHeartbeat as e:
        fail(str(e))
    typer.echo(json.dumps(summary) if as_json else format_summary(summary))
