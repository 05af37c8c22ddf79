"""``stack down``: stop the running stacks this machine addresses, and of a vehicle spread over several machines,
every host's share (or only the one ``--host`` names)."""

from __future__ import annotations

import json
import os
import signal
import time

import psutil
import typer
import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig
from stack.bus.node import Node
from stack.bus.query import query_json
from stack.bus.supervisors import SINGLE_HOST, rosters
from stack.cli.common import VehicleOption, fail, number
from stack.supervisor import state as run_state

POLL_S = 0.05


def down(
    vehicle: str | None = VehicleOption,
    host: str | None = typer.Option(
        None, "--host", help="Of a vehicle spread over machines: stop only this host's share (default: every host's)"
    ),
    timeout: float = typer.Option(30.0, callback=number(0), help="Seconds to wait for the stack to stop"),
) -> None:
    """Stop the running `stack up` stacks, or the flights if none runs, or the one named (its supervisor
    stops the modules in reverse order); a vehicle spread over machines is stopped on every host."""
    stacks = run_state.addressed_stacks(vehicle)
    if not stacks:
        fail("no running stack found")
    for s in stacks:
        own = str(s.get("host", SINGLE_HOST))
        if own != SINGLE_HOST and host != own:
            _stop_other_hosts(s, host, timeout)
        if host is None or host == own:
            _stop_local(s, timeout)
    typer.echo("stopped")


def _stop_local(s: dict[str, object], timeout: float) -> None:
    pid, name = int(s["pid"]), run_state.stack_name(s)
    os.kill(pid, signal.SIGTERM)
    typer.echo(f"stopping stack '{name}' (supervisor pid {pid})")
    if not _wait_exit(pid, timeout):
        fail(f"stack '{name}' did not stop within {timeout:g} s")


def _stop_other_hosts(s: dict[str, object], only: str | None, timeout: float) -> None:
    """Ask the supervisors of the vehicle's other hosts (or of ``only``) to stop, through this host's router, and
    wait until none of them answers any more."""
    vehicle, own = str(s["vehicle"]), str(s["host"])
    bus = BusConfig.from_json(json.dumps(s["bus"]))
    client = BusConfig(mode="client", connect=(str(s["endpoint"]),), listen=(), lease_ms=bus.lease_ms)
    try:
        node = Node(client, vehicle, f"down-{os.getpid()}", stable_id=False)
    except zenoh.ZError as e:
        fail(f"cannot reach the bus of host {own} to stop the others: {e}")
    with node:
        hosts = [only] if only else sorted({a["host"] for a in rosters(node.session, vehicle)} - {own})
        stopping = {
            str(a["host"]): a["pid"]
            for h in hosts
            for a in query_json(node.session, keys.supervisor_key(vehicle, h, "stop"))
        }
        if only is not None and only not in stopping:
            fail(f"host {only}: no supervisor of vehicle '{vehicle}' answers there")
        for name, pid in sorted(stopping.items()):
            typer.echo(f"stopping host {name} (supervisor pid {pid})")
        deadline = time.monotonic() + timeout
        while stopping.keys() & {a["host"] for a in rosters(node.session, vehicle)}:
            if time.monotonic() > deadline:
                fail(f"hosts {', '.join(sorted(stopping))} did not stop within {timeout:g} s")
            time.sleep(POLL_S)


def _wait_exit(pid: int, timeout: float) -> bool:
    """Wait until the process is gone (a zombie waiting for its parent counts as gone)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                return True
        except psutil.NoSuchProcess:
            return True
        time.sleep(POLL_S)
    return False
