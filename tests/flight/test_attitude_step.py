"""attitude_step on the default profile: its figures on three seeds, flown in one process (the ``stack fly``
flight, message for message, as test_inprocess_stack proves), and the report of the real CLI's flight, every
module its own process (the one test_determinism flies on both transports)."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from tests.flight.flights import ATTITUDE_STEP_TARGETS as TARGETS
from tests.flight.flights import Flight, InProcessFlight

pytestmark = pytest.mark.flight
Fly = Callable[..., Flight]
FlyHere = Callable[..., InProcessFlight]

# A limit holds only if it holds on every seed (benchmarks/sweep.py flies 20); CI flies three, each once.
SEEDS = (1, 2, 3)
CLI_SEED = 3

REPORT_KEYS = {
    "scenario",
    "profile",
    "seed",
    "passed",
    "sim_time_s",
    "wall_time_s",
    "realtime_factor",
    "metrics",
    "checks",
}


def test_report_format(fly: Fly) -> None:
    report = fly(CLI_SEED).report
    assert set(report) >= REPORT_KEYS
    assert report["scenario"] == "attitude_step"
    assert report["profile"] == "sitl_quad"
    assert report["seed"] == CLI_SEED
    assert isinstance(report["passed"], bool)
    # Arm, climb 3 m, settle, then six 1.5 s holds: well over 9 s simulated.
    assert report["sim_time_s"] > 9.0
    assert report["wall_time_s"] > 0.0
    assert report["realtime_factor"] == pytest.approx(report["sim_time_s"] / report["wall_time_s"])
    assert isinstance(report["metrics"], dict)
    assert all(isinstance(v, float) for v in report["metrics"].values())
    assert [c["name"] for c in report["checks"]] == list(TARGETS)
    for check in report["checks"]:
        assert set(check) == {"name", "value", "limit", "passed"}
        assert check["value"] == report["metrics"][check["name"]]
        assert isinstance(check["limit"], float)
        assert isinstance(check["passed"], bool)


def test_the_cli_says_the_flight_passed(fly: Fly) -> None:
    flight = fly(CLI_SEED)
    assert flight.returncode == 0, flight.output
    assert flight.report["passed"] is True
    assert "PASSED" in flight.output


@pytest.mark.parametrize("seed", SEEDS)
def test_every_check_passed(fly_here: FlyHere, seed: int) -> None:
    report = fly_here("attitude_step", seed).report
    assert report["passed"] is True
    assert report["error"] is None
    assert [c["name"] for c in report["checks"] if not c["passed"]] == []


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("metric", list(TARGETS))
def test_meets_the_scenarios_own_limit(fly_here: FlyHere, metric: str, seed: int) -> None:
    report = fly_here("attitude_step", seed).report
    value = report["metrics"][metric]
    assert math.isfinite(value)
    assert 0.0 <= value <= TARGETS[metric], f"{metric} = {value:.4g}, target {TARGETS[metric]}"
    if metric.endswith("_rise_time_s"):
        assert value > 0.0
    # The profile judges the flight by the scenario's own limits, not relaxed ones.
    limit = next(c["limit"] for c in report["checks"] if c["name"] == metric)
    assert limit == TARGETS[metric]
