"""`stack fly SCENARIO --vehicles N`: swarm scenarios flown by whole stacks, one per vehicle, in one world.

The followers hear the leader's position over the bus (the leader's fast path puts it on Zenoh for them) a fixed
100 ms late, waiting for it in lockstep, so a seed gives one swarm flight, figure for figure. Flown here on one
seed each; ``benchmarks/sweep.py --scenarios swarm_formation,swarm_leader_loss --seeds 1-20`` flies more.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stack.scenario.formation import LEADER_TIMEOUT_S
from tests.support.harness import run_cli, wait_no_processes
from tests.swarm.figures import FORMATION_METRICS, FORMATION_SEED

pytestmark = pytest.mark.flight
FLIGHT_TIMEOUT_S = 600.0


def fly_swarm(home: Path, scenario: str, vehicles: int, seed: int, name: str) -> tuple[dict, str]:
    report = home / f"{name}.json"
    out = run_cli(home, "fly", scenario, "--vehicles", str(vehicles), "--seed", str(seed), "--quiet",
                  "--report", str(report), timeout=FLIGHT_TIMEOUT_S)
    assert report.exists(), out.stdout[-3000:] + out.stderr[-3000:]
    return json.loads(report.read_text()), out.stdout + out.stderr


def test_two_vehicles_fly_the_box_abreast(tmp_path: Path) -> None:
    first, output = fly_swarm(tmp_path, "swarm_formation", 2, FORMATION_SEED, "first")
    assert first["passed"] is True and first["error"] is None, output[-4000:]
    assert first["vehicles"] == ["v1", "v2"]
    metrics = first["metrics"]
    assert metrics["formation_error_rms_m"] <= 0.5 and metrics["formation_error_max_m"] <= 1.5
    assert metrics["min_separation_m"] >= 3.0 and metrics["all_landed_and_disarmed"] is True
    follower = first["by_vehicle"]["v2"]["metrics"]
    assert follower["leader_lost_at"] is None and 0.1 <= follower["oldest_followed_s"] <= LEADER_TIMEOUT_S
    assert "Traceback" not in output
    assert metrics == FORMATION_METRICS  # as when each vehicle's modules share one process, or over two hosts
    assert wait_no_processes(tmp_path) == []


def test_followers_that_lose_their_leader_notice_within_a_second_hold_and_land_and_a_seed_is_one_flight(
    tmp_path: Path,
) -> None:
    report, output = fly_swarm(tmp_path, "swarm_leader_loss", 2, 1, "loss")
    assert report["passed"] is True and report["error"] is None, output[-4000:]
    metrics = report["metrics"]
    assert 0.0 < metrics["notice_time_max_s"] <= 1.0
    assert metrics["oldest_followed_max_s"] <= LEADER_TIMEOUT_S
    assert metrics["reacted_as_chosen"] is True and metrics["followers_landed_and_disarmed"] is True
    assert "v1: [scenario] INFO    t=43.99 s: killing every process of this vehicle" in output
    assert "[swarm] v1 was ended by SIGKILL" in output
    assert report["by_vehicle"]["v2"]["metrics"]["mode_after_loss"] == "Hold"
    again, output = fly_swarm(tmp_path, "swarm_leader_loss", 2, 1, "again")
    assert again["metrics"] == report["metrics"], output[-4000:]
    assert again["by_vehicle"] == report["by_vehicle"]
    assert wait_no_processes(tmp_path) == []


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (("takeoff_land", "--vehicles", "2"), "scenario takeoff_land flies one vehicle; the swarm scenarios: "),
        (("swarm_formation",), "scenario swarm_formation flies a swarm: give --vehicles N, N at least 2"),
        (("swarm_formation", "--vehicles", "2", "--plot"), "not with --plot"),
    ],
)
def test_a_swarm_flight_asked_for_wrongly_is_one_clear_error(tmp_path: Path, args: tuple[str, ...], said: str) -> None:
    out = run_cli(tmp_path, "fly", *args)
    assert out.returncode == 2 and said in out.stderr, out.stderr
    assert "Traceback" not in out.stderr
