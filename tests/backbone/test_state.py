"""The run registry in STACK_HOME: run directories that never collide, and which stack a command addresses."""

from __future__ import annotations

import os
import subprocess
import threading
from pathlib import Path

import psutil
import pytest

from stack.supervisor import state as run_state
from tests.support.harness import RunningStack, chain_profile, run_cli, wait_no_processes


@pytest.fixture
def home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    return tmp_path


def register(vehicle: str, pid: int, kind: str) -> dict[str, object]:
    state: dict[str, object] = {"pid": pid, "kind": kind, "vehicle": vehicle, "endpoint": "tcp/127.0.0.1:1"}
    run_state.write_state(vehicle, state)
    return state


def dead_pid() -> int:
    return next(p for p in range(4_000_000, 3_000_000, -1) if not psutil.pid_exists(p))


def test_stacks_started_in_the_same_second_get_their_own_run_directories(home, monkeypatch):
    monkeypatch.setattr(run_state.time, "strftime", lambda fmt: "20240101-120000")
    start = threading.Barrier(8)
    made: list[Path] = []

    def new() -> None:
        start.wait()
        made.append(run_state.new_run_dir("takeoff_land", "v1"))

    threads = [threading.Thread(target=new) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(p.name for p in made) == sorted(
        ["20240101-120000-takeoff_land-v1", *(f"20240101-120000-takeoff_land-v1-{n}" for n in range(2, 9))]
    )
    assert all(p.is_dir() for p in made)


def test_unnamed_commands_address_stack_up_then_the_flights_and_a_flight_by_its_name(home):
    flight_pid = os.getppid()
    flight = register("v1", flight_pid, run_state.FLY)
    up = register("v1", os.getpid(), run_state.UP)
    register("v2", dead_pid(), run_state.UP)
    assert run_state.addressed_stacks(None) == [up]
    assert run_state.addressed_stacks("v1") == [up]
    assert run_state.addressed_stacks(f"v1-fly-{flight_pid}") == [flight]
    assert run_state.stack_name(flight) == f"v1-fly-{flight_pid}"
    # The state of a supervisor that died without cleaning up is removed, not followed.
    assert sorted(p.name for p in (home / "state").iterdir()) == sorted(
        [f"v1.{flight_pid}.json", f"v1.{os.getpid()}.json"]
    )
    run_state.remove_state("v1", os.getpid())
    assert run_state.addressed_stacks(None) == [flight]


def test_several_flights_and_no_stack_up_ask_for_a_name(home):
    pids = (os.getpid(), os.getppid())
    for pid in pids:
        register("v1", pid, run_state.FLY)
    out = run_cli(home, "status")
    assert out.returncode == 1
    names = ", ".join(sorted(f"v1-fly-{pid}" for pid in pids))
    assert out.stderr.strip() == f"error: several stacks are running ({names}): choose one with --vehicle"
    out = run_cli(home, "status", "--vehicle", "v1")
    assert (
        out.stderr.strip() == "error: no running stack found named 'v1' (start one with `stack up`, or pass --endpoint)"
    )


def test_a_state_whose_pid_is_a_zombie_or_another_program_is_removed(home):
    me = register("v1", os.getpid(), run_state.UP) | run_state.process_identity()
    run_state.write_state("v1", me)
    assert run_state.addressed_stacks(None) == [me]
    # The pid now belongs to a program started after the supervisor that wrote the state.
    run_state.write_state("v1", me | {"pid_started": me["pid_started"] - 100})
    zombie = subprocess.Popen(["sleep", "0"])
    while psutil.Process(zombie.pid).status() != psutil.STATUS_ZOMBIE:
        pass
    register("v2", zombie.pid, run_state.UP)
    assert run_state.addressed_stacks(None) == []
    assert not list((home / "state").iterdir())
    zombie.wait()


def test_after_sigkill_of_the_supervisor_no_command_believes_a_stack_runs(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    try:
        stack.wait_up()
        assert len(list((home / "state").glob("*.json"))) == 1
        stack.proc.kill()  # SIGKILL: no clean-up, and not reaped yet (a zombie, as under a parent that never waits)
        for command in ("status", "down"):
            out = run_cli(home, command)
            assert out.returncode == 1
            assert out.stderr.startswith("error: no running stack found"), out.stderr
        assert not list((home / "state").glob("*.json"))
    finally:
        stack.kill()
    assert not wait_no_processes(home, timeout=15)
