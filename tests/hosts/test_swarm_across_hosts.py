"""A swarm spread over two hosts (network namespaces joined by a bridge) flies ``swarm_formation`` in one world.

Each host runs its share, ``stack fly swarm_formation --vehicles 2 --here vN`` (each vehicle's modules grouped),
with a STACK_HOME of its own, as separate machines would: the leader's host listens on its address, the follower's
joins it, over mutual TLS, each as its identity of one keystore. The world clock is kept over the bus, the follower
hears the leader across the link, and each host judges the whole swarm from both vehicles' results: both find the
same figures, those of the same flight on one machine.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from stack.security.keystore import init_keystore, issue_identity
from tests.hosts.split import ROUTER_PORT
from tests.support.harness import REPO, stack_env
from tests.swarm.figures import FORMATION_METRICS, FORMATION_SEED

pytestmark = [pytest.mark.timeout(600), pytest.mark.xdist_group("heavy_wall_clock")]


def test_a_swarm_over_two_hosts_flies_in_formation_in_one_world(network, tmp_path: Path) -> None:
    net = network(["lead", "follow"])
    lead, follow = net.hosts["lead"], net.hosts["follow"]
    endpoint = f"tls/{lead.address}:{ROUTER_PORT}"
    keystore = tmp_path / "keys"
    init_keystore(keystore)
    for host in (lead, follow):
        issue_identity(keystore, host.name, "host", (host.address,))
    fly = ("fly", "swarm_formation", "--vehicles", "2", "--seed", str(FORMATION_SEED))
    # each vehicle's lockstep modules in one process (half the CPU)
    fly += ("--quiet", "--profile", "sitl_quad_grouped")
    shares = {}
    for host, args in ((lead, ("--here", "v1", "--listen", endpoint)), (follow, ("--here", "v2", "--join", endpoint))):
        log = (tmp_path / f"{host.name}.log").open("w")
        report = str(tmp_path / f"{host.name}.json")
        who = ("--keystore", str(keystore), "--identity", host.name)
        shares[host.name] = host.popen(
            sys.executable, "-m", "stack", *who, *fly, *args, "--report", report, env=stack_env(host.home), stdout=log,
            stderr=subprocess.STDOUT, cwd=REPO,
        )  # fmt: skip
    for name, share in shares.items():
        share.wait(timeout=540)
        log = (tmp_path / f"{name}.log").read_text()
        assert share.returncode == 0, log[-4000:]
        assert "Traceback" not in log
    reports = {name: json.loads((tmp_path / f"{name}.json").read_text()) for name in shares}
    assert reports["lead"]["metrics"] == reports["follow"]["metrics"]
    assert reports["lead"]["by_vehicle"] == reports["follow"]["by_vehicle"]
    # the figures of one machine: bit for bit on the CPU they were taken on, within rounding on another (CPython's
    # libm and numpy choose their code by the CPU's instructions)
    assert reports["lead"]["metrics"] == pytest.approx(FORMATION_METRICS, rel=1e-9, abs=0)
    assert "v2: [scenario] INFO    t=24.99 s: in formation" in (tmp_path / "follow.log").read_text()
