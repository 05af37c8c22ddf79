"""Publish and subscribe across real processes over Zenoh on loopback; bad input is counted and dropped."""

import contextlib
import json
import subprocess
import sys

from stack.bus.node import stable_publisher_id
from stack.bus.ports import free_port
from tests.support.harness import REPO, RunningStack, chain_profile, eventually, stack_env, wait_no_processes


def test_messages_cross_processes_in_order_with_header(tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    out = tmp_path / "received.json"
    env = stack_env(tmp_path / "home")
    sub = subprocess.Popen(
        [sys.executable, "-m", "tests.support.peers", "sub", endpoint, "500", str(out)], env=env, cwd=REPO
    )
    pub = subprocess.Popen([sys.executable, "-m", "tests.support.peers", "pub", endpoint, "500"], env=env, cwd=REPO)
    assert pub.wait(timeout=60) == 0
    assert sub.wait(timeout=60) == 0
    got = json.loads(out.read_text())
    assert [m["param1"] for m in got] == [float(i) for i in range(500)]
    assert all(m["command"] == 400 for m in got)
    assert {m["publisher"] for m in got} == {stable_publisher_id("t1", "test_publisher")}
    seqs = [m["seq"] for m in got]
    assert seqs == sorted(seqs) and len(set(seqs)) == 500
    assert all(m["t"] == -1 for m in got)  # wall-clock publisher: not lockstep time


def test_malformed_and_mismatched_samples_are_counted_and_dropped(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml", lockstep=False, extra='[[module]]\nmodule = "tests.support.modules:CommandCounter"\n'
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        rogue = subprocess.run(
            [sys.executable, "-m", "tests.support.peers", "rogue"], env=stack_env(home), cwd=REPO, timeout=60
        )
        assert rogue.returncode == 0

        def counter() -> dict:
            return next(m for m in stack.status()["modules"] if m["module"] == "command_counter")

        with contextlib.suppress(AssertionError):  # a heartbeat carries the counters; the assertions say what differs
            eventually(lambda: counter()["schema_errors"] >= 40, what="the counters in a heartbeat")
        assert (counter()["decode_errors"], counter()["schema_errors"]) == (20, 40)
        runs_before = counter()["runs"]
        eventually(lambda: counter()["runs"] > runs_before, what="the counter running on")
        assert counter()["state"] == "running"
        assert "schema mismatch" in stack.output and "malformed" in stack.output
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)
