"""`stack fly SCENARIO --vehicles N`: swarm scenarios flown by whole stacks, one per vehicle, in one world.

The followers hear the leader's position over the bus (the leader's fast path puts it on Zenoh for them) a fixed
100 ms late, waiting for it in lockstep, so a seed gives one swarm flight, figure for figure
(tests/hosts/test_swarm_across_hosts.py flies swarm_formation over two hosts and finds the figures of one machine).
Flown here on one seed; ``benchmarks/sweep.py --scenarios swarm_formation,swarm_leader_loss --seeds 1-20`` flies
more.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stack.scenario.formation import LEADER_TIMEOUT_S
from tests.support.harness import run_cli, wait_no_processes

pytestmark = pytest.mark.flight
FLIGHT_TIMEOUT_S = 600.0


def fly_swarm(home: Path, scenario: str, vehicles: int, seed: int, name: str) -> tuple[dict, str]:
    report = home / f"{name}.json"
    out = run_cli(home, "fly", scenario, "--vehicles", str(vehicles), "--seed", str(seed), "--quiet",
                  "--report", str(report), timeout=FLIGHT_TIMEOUT_S)
    assert report.exists(), out.stdout[-3000:] + out.stderr[-3000:]
    return json.loads(report.read_text()), out.stdout + out.stderr


def test_followers_that_lose_their_leader_notice_within_a_second_hold_and_land(tmp_path: Path) -> None:
    report, output = fly_swarm(tmp_path, "swarm_leader_loss", 2, 1, "loss")
    assert report["passed"] is True and report["error"] is None, output[-4000:]
    metrics = report["metrics"]
    assert 0.0 < metrics["notice_time_max_s"] <= 1.0
    assert metrics["oldest_followed_max_s"] <= LEADER_TIMEOUT_S
    assert metrics["reacted_as_chosen"] is True and metrics["followers_landed_and_disarmed"] is True
    assert "v1: [scenario] INFO    t=43.99 s: killing every process of this vehicle" in output
    assert "[swarm] v1 was ended by SIGKILL" in output
    assert report["by_vehicle"]["v2"]["metrics"]["mode_after_loss"] == "Hold"
    assert wait_no_processes(tmp_path) == []


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (("takeoff_land", "--vehicles", "2"), "scenario takeoff_land flies one vehicle; the swarm scenarios: "),
        (("swarm_formation",), "scenario swarm_formation flies a swarm: give --vehicles N, N at least 2"),
        (("swarm_formation", "--vehicles", "2", "--plot"), "not with --plot"),
        (("swarm_formation", "--vehicles", "2", "--here", "v3", "--join", "tcp/127.0.0.1:1"), "--here: no vehicle v3"),
        (("swarm_formation", "--vehicles", "2", "--here", "v1"), "--here: the other machines' shares reach this one"),
        (("takeoff_land", "--listen", "tcp/127.0.0.1:1"), "--listen: a share of a swarm flight"),
    ],
)
def test_a_swarm_flight_asked_for_wrongly_is_one_clear_error(tmp_path: Path, args: tuple[str, ...], said: str) -> None:
    out = run_cli(tmp_path, "fly", *args)
    assert out.returncode == 2 and said in out.stderr, out.stderr
    assert "Traceback" not in out.stderr
