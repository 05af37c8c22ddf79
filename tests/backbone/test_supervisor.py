"""The supervisor: start order, restarts, clean stops with no orphans, exit codes, status."""

import json
import re
import signal
import socket

import psutil
import pytest

from tests.support.harness import RunningStack, chain_profile, eventually, run_cli, wait_no_processes, write_profile


def test_modules_start_in_order_each_after_the_previous_is_ready_and_stop_in_reverse(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    try:
        stack.wait_up()
        pids = stack.module_pids()
        assert list(pids) == ["tick_source", "doubler", "summer", "pacer"]
    finally:
        assert stack.stop(signal.SIGINT) == 0
    events = re.findall(r"\[stack\] (starting (\w+)|(\w+) ready)", stack.output)
    names = ["tick_source", "doubler", "summer", "pacer"]
    expected = [x for n in names for x in (f"starting {n}", f"{n} ready")]
    assert [e[0].split(" (pid")[0] for e in events] == expected
    stopped = re.findall(r"\[(\w+)\] INFO\s+stopped \(SIGTERM\)", stack.output)
    assert stopped == list(reversed(names))
    assert not wait_no_processes(home)
    assert not any(psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE for p in pids.values())


def test_duration_and_logs_per_module(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False), "--duration", "3")
    run_dir = stack.run_dir()
    assert stack.wait(timeout=90) == 0
    assert "duration of 3 s reached" in stack.output
    for name in ("tick_source", "doubler", "summer", "pacer"):
        text = (run_dir / f"{name}.log").read_text()
        assert f"{name} ready" in text and "stopped (SIGTERM)" in text
        assert "taken, listening on another port" not in text  # its port was held for it until it started
        assert (run_dir / f"{name}.spec.json").exists()
    assert "[doubler] INFO    doubler ready" in stack.output
    assert not wait_no_processes(home)


def test_crashed_module_is_restarted_with_backoff_then_given_up(tmp_path):
    home = tmp_path / "home"
    marker = tmp_path / "starts.txt"
    profile = write_profile(
        tmp_path / "crash.toml",
        f"""
[stack]
vehicle = "t1"
lockstep = false

[[module]]
module = "tests.support.modules:CommandCounter"

[[module]]
module = "tests.support.modules:Crasher"
args = {{ ticks = 4, marker = "{marker}" }}
restart = "on-failure"
max_restarts = 3
""",
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_for(r"starting crasher")
        listen = json.loads((stack.run_dir() / "crasher.spec.json").read_text())["bus"]["listen"][0]
        port = int(listen.rpartition(":")[2])
        stack.wait_for(r"crasher: restart in 0.5 s", timeout=90)
        # Until it is given up (3.5 s of backoff on), the crasher's port is held for its restarts or listened on.
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as stranger, pytest.raises(OSError):
            stranger.bind(("127.0.0.1", port))
        stack.wait_for(r"crasher: giving up after 3 restarts", timeout=90)
        assert "taken" not in (stack.run_dir() / "crasher.log").read_text()
        assert len(marker.read_text().split()) == 4
        for n in (1, 2, 3):
            assert f"restarting crasher (restart {n})" in stack.output
        assert all(f"crasher: restart in {delay} s" in stack.output for delay in ("0.5", "1.0", "2.0"))
        assert "crasher failed with exit code 4" in stack.output
        assert stack.status()["modules"][0]["state"] == "running"
    finally:
        code = stack.stop()
    assert code == 1
    assert not wait_no_processes(home)


def test_a_module_that_cannot_start_fails_the_stack(tmp_path):
    home = tmp_path / "home"
    profile = write_profile(
        tmp_path / "broken.toml",
        """
[stack]
vehicle = "t1"
lockstep = false

[[module]]
module = "tests.support.modules:CommandCounter"

[[module]]
module = "tests.support.modules:BrokenInit"

[[module]]
module = "tests.support.modules:Pacer"
""",
    )
    stack = RunningStack(home, profile)
    assert stack.wait(timeout=90) == 1
    assert "broken_init exited with code 1 while starting" in stack.output
    assert "cannot start: the hardware is missing" in stack.output
    assert "starting pacer" not in stack.output
    assert not wait_no_processes(home)


def test_stack_down_and_sigterm_stop_everything(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    stack.wait_up()
    down = run_cli(home, "down")
    assert down.returncode == 0 and "stopped" in down.stdout
    assert stack.wait(timeout=30) == 0
    assert not wait_no_processes(home)
    assert run_cli(home, "status").returncode == 1

    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    stack.wait_up()
    assert stack.stop(signal.SIGTERM) == 0
    assert not wait_no_processes(home)


def test_no_module_outlives_a_killed_supervisor(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    stack.wait_up()
    pids = stack.module_pids()
    stack.proc.kill()
    stack.proc.wait()
    assert not wait_no_processes(home, timeout=15)

    def alive(pid: int) -> bool:
        try:
            return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return False

    eventually(lambda: not any(alive(p) for p in pids.values()), timeout=15, what="every module gone")


def test_status_reports_each_module(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    try:
        stack.wait_up()

        def measured() -> bool:  # a heartbeat's window after start-up (the first one's holds the start-up)
            rates = {m["module"]: m.get("trigger_rate_hz", 0.0) for m in stack.status()["modules"]}  # none before one
            return 200 < rates.get("doubler", 0) < 300 and 40 < rates.get("pacer", 0) < 60

        eventually(measured, what="the doubler's and the pacer's trigger rates")
        report = stack.status()
        rows = {m["module"]: m for m in report["modules"]}
        assert set(rows) == {"tick_source", "doubler", "summer", "pacer"}
        for row in rows.values():
            assert row["state"] == "running" and row["pid"] > 0 and row["rss_bytes"] > 10_000_000
            assert row["restarts"] == 0 and row["runs"] > 0
        assert 200 < rows["doubler"]["trigger_rate_hz"] < 300
        assert 40 < rows["pacer"]["trigger_rate_hz"] < 60
        assert rows["doubler"]["trigger"] == "on sensor_gyro"
        table = stack.cli("status").stdout
        assert "MODULE" in table and "CPU%" in table and "RESTARTS" in table and "doubler" in table
    finally:
        stack.stop()
    assert not wait_no_processes(home)


def test_ctrl_c_during_start_up_says_it_was_interrupted_and_what_had_started(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml", lockstep=False, extra='\n[[module]]\nmodule = "tests.support.modules:SlowStart"\n'
    )
    for sig, code in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
        stack = RunningStack(home, profile)
        try:
            stack.wait_for(r"starting slow_start")
            assert stack.stop(sig) == code
        finally:
            stack.kill()
        name = signal.Signals(sig).name
        assert (
            f"start-up interrupted by {name}: 4 of 5 started (tick_source, doubler, summer, pacer), "
            "slow_start starting; stopping them"
        ) in stack.output
        assert stack.output.rstrip().endswith("[stack] stopped: start-up interrupted")
        assert "failures" not in stack.output and "exit code" not in stack.output
        assert not wait_no_processes(home)
        assert run_cli(home, "status").returncode == 1
