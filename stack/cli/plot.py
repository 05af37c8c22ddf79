"""``stack plot``: live Rerun plots of a running stack, from another terminal.

The command runs the ``rerun_bridge`` module in this process, as a Zenoh client of the stack's
router: the same code as ``stack up --plot``, attached late. It stays outside the lockstep like any
passive module and stops cleanly on Ctrl-C, SIGTERM or ``--duration``. With no display and neither
``--web`` nor ``--save`` it says so and exits, rather than plot to nowhere.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
from types import FrameType

import typer

from stack.bus.config import BusConfig
from stack.bus.supervisors import vehicle_status
from stack.cli.common import (
    EndpointOption,
    VehicleOption,
    fail,
    find_stack,
    number,
    open_bus,
    output_file,
    vehicle_on_bus,
)
from stack.runtime.spec import ModuleSpec
from stack.viz.display import DEFAULT_GRPC_PORT, has_display


def _probe(vehicle: str, endpoint: str | None, bus: BusConfig) -> tuple[str, bool]:
    """The vehicle (checked on the bus when reached by ``endpoint``), and whether it runs in lockstep (its timestamps
    are then simulated time from zero)."""
    session = open_bus(bus, f"plot-probe-{os.getpid()}")
    try:
        if endpoint:
            vehicle = vehicle_on_bus(session, vehicle or None, endpoint)
        status = vehicle_status(session, vehicle)
    finally:
        session.close()
    return vehicle, bool(status and status.get("lockstep"))


def _stop_on_signals() -> None:
    """SIGINT, SIGTERM and the --duration alarm unwind the bridge once; repeats are ignored meanwhile."""
    from stack.runtime.runner import Shutdown

    stopping: list[bool] = []

    def on_signal(signum: int, frame: FrameType | None) -> None:
        if stopping:
            return
        stopping.append(True)
        raise Shutdown(signal.Signals(signum).name)

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGALRM):
        signal.signal(sig, on_signal)


def plot(
    web: bool = typer.Option(False, "--web", help="Serve the web viewer (on 127.0.0.1) instead of a native viewer"),
    save: str = typer.Option("", "--save", callback=output_file, help="Also write the plots to this .rrd file"),
    plot_rate: float = typer.Option(
        50.0, "--plot-rate", callback=number(0), help="Most rows per second per topic (0: every message)"
    ),
    window: float = typer.Option(
        30.0, "--window", callback=number(0), help="Seconds of data the time series show (0: all)"
    ),
    bind: str = typer.Option("127.0.0.1", "--bind", help="Address the viewer servers listen on"),
    grpc_port: int | None = typer.Option(
        None,
        "--grpc-port",
        min=0,
        max=65535,
        help=f"Viewer data port (0: any free port; default: {DEFAULT_GRPC_PORT}, any with --web)",
    ),
    web_port: int | None = typer.Option(
        None, "--web-port", min=0, max=65535, help="Web viewer page port (default: any free port)"
    ),
    duration: float = typer.Option(
        0.0, "--duration", "-d", callback=number(0), help="Seconds of plotting, then stop (0: until Ctrl-C)"
    ),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    all_: bool = typer.Option(
        False, "--all", help="Every vehicle on the bus in one view: positions, heights, speeds, batteries, modes"
    ),
) -> None:
    """Live plots of a running stack in Rerun: attitude, rates, motors, position, estimator, 3D view."""
    from stack.runtime.runner import Runtime, Shutdown, shutdown_behind  # the module runtime, only when plotting

    if not web and not save and not has_display():
        fail("no display here for the Rerun viewer: use --web (a viewer in the browser) or --save FILE.rrd")
    if all_:
        if vehicle is not None:
            fail("--all plots every vehicle: give it or --vehicle, not both", code=2)
        from stack.cli.swarm_plot import plot_swarm

        _stop_on_signals()
        if duration > 0:
            signal.setitimer(signal.ITIMER_REAL, duration)
        sinks = {"save": save, "web": web, "spawn": not web and has_display(), "bind": bind}
        sinks |= {"grpc_port": (0 if web else DEFAULT_GRPC_PORT) if grpc_port is None else grpc_port}
        sinks |= {"web_port": 0 if web_port is None else web_port}
        try:
            plot_swarm(endpoint, sinks, window or None)
        except Shutdown:
            pass
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        typer.echo("plot stopped")
        return
    vehicle_name, bus = find_stack(vehicle, endpoint)
    vehicle_name, lockstep = _probe(vehicle_name, endpoint, bus)
    spec = ModuleSpec(
        name=f"plot-{os.getpid()}",
        module="rerun_bridge",
        vehicle=vehicle_name,
        bus=bus,
        args={
            "spawn": not web,
            "web": web,
            "save": save,
            "bind": bind,
            # A web viewer of its own on free ports; the native viewer's usual port joins one already open.
            "grpc_port": (0 if web else DEFAULT_GRPC_PORT) if grpc_port is None else grpc_port,
            "web_port": 0 if web_port is None else web_port,
            "plot_rate_hz": plot_rate,
            "window_s": window,
        },
        lockstep=lockstep,
        late_join=True,  # the stack is running (or is a replay): no start-up sync
    )
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stdout, force=True)
    _stop_on_signals()

    def start_the_clock() -> None:
        # --duration counts plotting time: on a loaded machine, setting up Rerun can take seconds.
        if duration > 0:
            signal.setitimer(signal.ITIMER_REAL, duration)

    try:
        Runtime(spec).run(on_ready=start_the_clock)
    except Shutdown:
        pass
    except (ValueError, RuntimeError) as e:
        if shutdown_behind(e) is None:
            fail(str(e))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    typer.echo("plot stopped")
