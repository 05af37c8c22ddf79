"""The default quad flown over two hosts of a test network: ``stack fly`` on the simulator's host, ``stack up`` on
the flight-control host (tests/support/hosts.py makes the hosts)."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from tests.flight.flights import FLY_TIMEOUT_S, Flight
from tests.support.harness import REPO, stack_env, write_profile
from tests.support.hosts import Host, Network

ROUTER_PORT = 7447  # inside namespaces of the test's own: nothing else listens there


def split_profile(path: Path, net: Network, extra: str = "", hosts: Sequence[Host] | None = None) -> Path:
    """``sitl_quad_hosts`` with the endpoints of the network's hosts (those it has, or ``hosts``), and ``extra``
    TOML."""
    chosen = net.hosts.values() if hosts is None else hosts
    endpoints = "\n".join(f'[hosts.{h.name}]\nendpoint = "tcp/{h.address}:{ROUTER_PORT}"\n' for h in chosen)
    return write_profile(path, f'extends = "sitl_quad_hosts"\n\n{endpoints}\n{extra}')


def stack_on(host: Host, *args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    """A ``stack`` command run on ``host``."""
    return host.run(sys.executable, "-m", "stack", *args, env=stack_env(host.home), timeout=timeout, cwd=REPO)


def take_off(host: Host, altitude: float) -> bool:
    """``stack cmd takeoff --wait`` from ``host``, for ``eventually``: False while arming is refused (a stack just
    up, or a host back, whose estimates still converge); a takeoff accepted must complete."""
    out = stack_on(host, "cmd", "takeoff", "--alt", str(altitude), "--wait")
    if "Arming denied" in out.stdout + out.stderr:
        return False
    assert out.returncode == 0 and "takeoff complete" in out.stdout, out.stdout + out.stderr
    return True


TAKEOFF_TIMEOUT_S = 90.0


def up_on(host: Host, profile: Path, log: Path, *args: str) -> subprocess.Popen[str]:
    """``stack up PROFILE --host NAME`` on ``host``, its output in ``log``."""
    return host.popen(
        sys.executable, "-m", "stack", "up", str(profile), "--host", host.name, "--quiet", "--insecure", *args,
        env=stack_env(host.home), stdout=log.open("w"), stderr=subprocess.STDOUT, cwd=REPO,
    )  # fmt: skip


# The MAVLink links run on the simulator's host: a flight leaves them out, and no host then waits for the ground.
LINKS_BESIDE_THE_SIMULATOR = """
[[module]]
name = "mavlink_gcs"
host = "sim"

[[module]]
name = "mavlink_api"
host = "sim"
"""


def fly_across_hosts(
    net: Network, scenario: str, seed: int, work: Path, keystore: Path | None = None, count_denials: bool = True
) -> Flight:
    """``stack fly SCENARIO --seed SEED --host sim`` with a report and a recording, flight control on the network's
    host ``control``; that host's stack is stopped once the flight is over. With ``keystore`` (an identity for each
    host), the links between the hosts are mutual TLS with its access rules (their denials counted, unless not
    ``count_denials``)."""
    sim, control = net.hosts["sim"], net.hosts["control"]
    secure = f'[security]\nkeystore = "{keystore}"\n' if keystore is not None else ""
    secure += "count_denials = false\n" if keystore is not None and not count_denials else ""
    profile = split_profile(work / "split.toml", net, LINKS_BESIDE_THE_SIMULATOR + secure)
    report, recording = work / "report.json", work / "flight.mcap"
    controls = up_on(control, profile, work / "control.log")
    try:
        out = stack_on(
            sim,
            *("fly", scenario, "--profile", str(profile), "--host", "sim", "--seed", str(seed), "--quiet"),
            *("--insecure", "--report", str(report), "--record", str(recording)),
            timeout=FLY_TIMEOUT_S,
        )
    finally:
        stack_on(control, "down")
        controls.wait(timeout=60)
    output = out.stdout + out.stderr + (work / "control.log").read_text()
    assert report.exists(), f"no report (exit code {out.returncode}):\n{output}"
    return Flight(out.returncode, output, json.loads(report.read_text()), recording)
