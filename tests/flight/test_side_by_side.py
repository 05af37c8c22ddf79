"""Flights side by side: two ``stack fly`` at once beside a ``stack up`` of the same vehicle, in one STACK_HOME.

Each flight is a stack of its own (its bus, ports, run directory and state): both pass, and the seed-1
flight is the same as one flown alone (lockstep: the same seed gives the same flight, whatever runs
beside it). Meanwhile the ``stack up`` stack is unaffected: same module processes, still on the ground,
and still what commands that name no stack address; a flight is addressed by its name.
"""

from __future__ import annotations

import json
import signal
from collections.abc import Callable
from pathlib import Path

import pytest

from stack.supervisor import state as run_state
from tests.flight.flights import FLY_TIMEOUT_S, InProcessFlight
from tests.support.harness import RunningStack, launch_profile, wait_no_processes

pytestmark = pytest.mark.flight

SCENARIO = "takeoff_land"
SEEDS = (1, 2)


def heights(stack: RunningStack, name: str | None = None) -> list[float]:
    """Heights above home [m] (``-z``) from ``stack topic echo``, of the named stack or the default one."""
    which = ("--vehicle", name) if name else ()
    out = stack.cli("topic", "echo", "vehicle_local_position", "-n", "5", "--field", "z", "--json", *which)
    assert out.returncode == 0, out.stderr
    return [-float(line) for line in out.stdout.split()]


def module_pids(status: dict) -> dict[str, int]:
    return {m["module"]: m["pid"] for m in status["modules"]}


def test_two_flights_and_a_stack_up_of_the_same_vehicle_run_side_by_side(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fly_here: Callable[..., InProcessFlight]
) -> None:
    home = tmp_path / "home"
    monkeypatch.setenv("STACK_HOME", str(home))
    up = RunningStack(home, launch_profile(tmp_path / "profile"), "--quiet", "--speed", "1")  # it stays on the ground
    flights: list[RunningStack] = []
    try:
        up.wait_up()
        before = up.status()
        reports = [tmp_path / f"report-{seed}.json" for seed in SEEDS]
        flights = [
            RunningStack(home, SCENARIO, "--seed", str(seed), "--quiet", "--report", str(report), command="fly")
            for seed, report in zip(SEEDS, reports, strict=True)
        ]
        names = [f.wait_for(r"\[stack\] flight '(\S+)'").group(1) for f in flights]
        assert names == [run_state.flight_name("v1", f.proc.pid) for f in flights]
        # Each flight answers by its name while in the air; unnamed, the commands still reach
        # `stack up`'s vehicle, on the ground and with the same processes.
        for f, name in zip(flights, names, strict=True):
            f.wait_for("holding for 20 s", timeout=FLY_TIMEOUT_S)
            assert min(heights(up, name)) > 1.0
            assert "scenario" in module_pids(json.loads(up.cli("status", "--vehicle", name, "--json").stdout))
        assert max(abs(h) for h in heights(up)) < 0.5
        assert module_pids(up.status()) == module_pids(before)

        assert [f.wait(timeout=FLY_TIMEOUT_S) for f in flights] == [0, 0], "\n".join(f.output for f in flights)
        assert up.proc.poll() is None
        after = up.status()
        assert module_pids(after) == module_pids(before)
        assert all(m["state"] == "running" and m["restarts"] == 0 for m in after["modules"])
        assert [s["kind"] for s in run_state.running_stacks()] == [run_state.UP]

        results = [json.loads(r.read_text()) for r in reports]
        assert all(r["passed"] for r in results)
        assert len({r["run_dir"] for r in results}) == 2
        alone = fly_here(SCENARIO, 1).report  # the same flight as `stack fly` alone, message for message
        assert results[0]["metrics"] == alone["metrics"]
        assert results[0]["sim_time_s"] == alone["sim_time_s"]

        down = up.cli("down")
        assert down.returncode == 0, down.stderr
        assert down.stdout.startswith("stopping stack 'v1'")
        assert up.wait(timeout=60.0) == 0
    finally:
        for f in flights:
            f.stop(signal.SIGINT)
        up.stop(signal.SIGINT)
    assert wait_no_processes(home) == []
