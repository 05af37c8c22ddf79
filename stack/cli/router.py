"""``stack router PROFILE --host NAME``: a host's Zenoh router and nothing else.

For a machine of the vehicle that runs no module, or only tools (a ground laptop with ``stack status``,
``stack plot`` and QGroundControl): it listens where the profile's ``[hosts.NAME]`` says, connects to the
other hosts' routers, and is the local rendezvous the tools of this machine find, as a ``stack up`` would be.
"""

from __future__ import annotations

import json
import math
import os
import signal
import time
from pathlib import Path

import typer
import zenoh

from stack.bus.config import BusConfig, open_router, without_link_options
from stack.bus.ports import free_port
from stack.cli.common import InsecureOption, KeystoreOption, check_exposure, fail, number
from stack.runtime.stop_event import StopEvent
from stack.security.denials import Denial, DenialCounts
from stack.supervisor import state as run_state
from stack.supervisor.profile import ProfileError, load_profile

SIGNAL_CHECK_S = 0.2


def router(
    profile: str = typer.Argument(..., help="Launch profile that spreads the vehicle over [hosts]"),
    host: str = typer.Option(..., "--host", help="The host of the profile this machine is"),
    duration: float | None = typer.Option(
        None, "--duration", "-d", callback=number(0), help="Stop after this many seconds"
    ),
    insecure: bool = InsecureOption,
    keystore: Path | None = KeystoreOption,
) -> None:
    """Run this host's Zenoh router of a vehicle spread over several machines, until Ctrl-C or SIGTERM."""
    try:
        prof = load_profile(profile)
        prof.check_host(host)
    except ProfileError as e:
        fail(str(e), code=2)
    check_exposure(prof, host, insecure, keystore)
    loopback = f"tcp/127.0.0.1:{free_port()}"
    beyond, connect = prof.router_links(host)
    listen = (loopback, *beyond)
    tls, access = prof.host_tls(host), prof.host_access()
    lease = prof.router_lease_ms
    bus = BusConfig(mode="router", listen=listen, connect=connect, lease_ms=lease, tls=tls, access=access)
    stop = StopEvent()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    denied = DenialCounts()

    def on_denial(denial: Denial) -> None:
        if denied.add(denial, time.time()):
            typer.echo(f"[stack] router of host {host}: {denial.describe()}")

    try:
        session = open_router(bus, f"router-{host}", prof.router_link_count, on_denial if prof.count_denials else None)
    except zenoh.ZError as e:
        fail(f"host {host}: cannot open its router on {', '.join(map(without_link_options, listen))}: {e}")
    client = BusConfig(mode="client", connect=(loopback,), listen=(), lease_ms=prof.bus.lease_ms)
    record = {
        **run_state.process_identity(),
        "kind": run_state.ROUTER,
        "vehicle": prof.vehicle,
        "host": host,
        "profile": str(prof.path),
        "endpoint": loopback,
        "bus": json.loads(client.to_json()),
        "started": time.time(),
    }
    run_state.write_state(prof.vehicle, record)
    try:
        others = ", ".join(connect) or "no other host"
        typer.echo(f"[stack] router of host {host}, vehicle '{prof.vehicle}': on {', '.join(listen)}; to {others}")
        end = time.monotonic() + duration if duration is not None else math.inf
        # in short waits: a signal that lands on one of Zenoh's threads is handled only once this one runs again
        while not stop.is_set() and time.monotonic() < end:
            stop.wait(min(SIGNAL_CHECK_S, end - time.monotonic()))
    finally:
        run_state.remove_state(prof.vehicle, os.getpid())
        session.close()
    typer.echo(f"[stack] router stopped ({denied.total} messages denied)" if denied.total else "[stack] router stopped")
