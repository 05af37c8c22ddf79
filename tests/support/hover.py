"""A real-time stack hovering, read and poked through the CLI: for the control-loss tests and benchmark."""

from __future__ import annotations

import json
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path

from tests.support.harness import RunningStack, launch_profile


def echo(stack: RunningStack, topic: str) -> dict:
    """The next message of a topic, as JSON."""
    out = stack.cli("topic", "echo", topic, "-n", "1", "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.splitlines()[0])


POLL_S = 0.5
"""Between two looks: each look is a CLI process, and a look every 0.2 s kept one core of two half busy, which
starved the real-time stack it watched."""


def wait(stack: RunningStack, ok: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not ok():
        assert time.monotonic() < deadline, f"no {what} within {timeout:g} s\n{stack.output}"
        time.sleep(POLL_S)


def start_hovering(home: Path, altitude: float) -> RunningStack:
    """``stack up sitl_quad --realtime``, taken off to ``altitude`` and settled there."""
    stack = RunningStack(home, launch_profile(home.parent / "profile"), "--realtime", "--quiet")
    try:
        stack.wait_up()
        deadline = time.monotonic() + 120.0
        while stack.cli("cmd", "takeoff", "--alt", str(altitude)).returncode != 0:  # until the pre-arm checks pass
            assert time.monotonic() < deadline, stack.output
            time.sleep(POLL_S)

        def settled() -> bool:
            here = echo(stack, "vehicle_local_position")
            return -here["z"] > altitude - 0.5 and abs(here["vz"]) < 0.2

        wait(stack, settled, 60.0, "the climb")
    except BaseException:
        stack.stop()
        raise
    return stack


def truth(stack: RunningStack) -> tuple[float, float, float]:
    """Where the simulated vehicle truly is (NED about the simulator's home point): after a crash the estimate
    may say anything."""
    north, east, down = echo(stack, "sim_groundtruth")["position"]
    return north, east, down


def kill(stack: RunningStack, module: str) -> tuple[float, float, float, int]:
    """SIGKILL a module; returns where the vehicle truly was (north, east, down) and when (the stack's clock, µs)."""
    here = truth(stack)
    pid = stack.module_pids()[module]
    killed_at = time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000
    os.kill(pid, signal.SIGKILL)
    return *here, killed_at


def restarted(stack: RunningStack, module: str) -> bool:
    modules = stack.status()["modules"]
    return any(m["module"] == module and m["restarts"] >= 1 and m["state"] == "running" for m in modules)
