"""`stack up --speed`: the lockstep paced to a factor of the wall clock (as PX4 SITL's PX4_SIM_SPEED_FACTOR)."""

import time

import pytest
import typer

from stack.cli import app as cli_app
from stack.runtime.pacing import SPEED_ENV
from stack.supervisor.profile import load_profile
from tests.support.harness import RunningStack, chain_profile, run_cli, wait_no_processes

STEPS = 1000  # 4 s of simulated time at 250 Hz


@pytest.mark.parametrize("transport", ["shm", "zenoh"])
def test_simulated_time_runs_at_the_speed_asked_and_status_says_so(tmp_path, transport):
    home = tmp_path / "home"
    profile = chain_profile(tmp_path / "chain.toml", tick_args=f"steps = {STEPS}", transport=transport)
    stack = RunningStack(home, profile, "--speed", "2")
    try:
        stack.wait_up()
        started = time.monotonic()
        status = stack.cli("status")
        assert "(lockstep, at 2x real time)" in status.stdout.splitlines()[0], status.stdout
        assert stack.wait(timeout=120) == 0, stack.output
        elapsed = time.monotonic() - started
    finally:
        stack.kill()
    assert not wait_no_processes(home)
    simulated = STEPS * 0.004
    # Never faster than asked (the wall clock is the pace); slower only on a starved machine.
    assert simulated / 2 * 0.95 <= elapsed < simulated / 2 * 4, elapsed


def test_a_speed_is_refused_where_there_is_no_lockstep_or_no_factor(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(tmp_path / "chain.toml", tick_args="steps = 10")
    for args, says in (
        (("--speed", "2", "--realtime"), "--speed paces the lockstep and --realtime runs without one"),
        (("--speed", "0.0.1"), "--speed: speed must be a factor > 0"),
        (("--speed", "-1"), "--speed: speed must be a factor > 0"),
        (("--speed", "nan"), "--speed: speed must be a factor > 0"),
    ):
        out = run_cli(home, "up", str(profile), *args)
        assert out.returncode == 2 and says in out.stderr, (args, out.stderr)
    wall_clock = chain_profile(tmp_path / "wall.toml", lockstep=False)
    out = run_cli(home, "up", str(wall_clock), "--speed", "2")
    assert out.returncode == 2 and "runs without lockstep, on the wall clock" in out.stderr, out.stderr


def test_without_speed_the_lockstep_runs_at_real_speed_unless_the_environment_says(tmp_path, monkeypatch):
    lockstep = load_profile(str(chain_profile(tmp_path / "chain.toml")))
    monkeypatch.delenv(SPEED_ENV, raising=False)
    assert cli_app._speed(lockstep, None, realtime=False) == 1.0
    monkeypatch.setenv(SPEED_ENV, "max")
    assert cli_app._speed(lockstep, None, realtime=False) == 0.0
    assert cli_app._speed(lockstep, "3", realtime=False) == 3.0  # the option wins
    monkeypatch.setenv(SPEED_ENV, "fast")
    with pytest.raises(typer.Exit):
        cli_app._speed(lockstep, None, realtime=False)
