"""A vehicle a swarm's launcher started ends with the launcher (stack.cli.swarm_launch.vehicle_of_swarm): killed
outright, the launcher cannot stop its vehicles, so the kernel does (SIGTERM on the parent's death)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from stack.cli.swarm_launch import LAUNCHER_ENV
from tests.support.harness import REPO

VEHICLE = """
import sys, time
from stack.cli.swarm_launch import vehicle_of_swarm
from stack.supervisor.profile import load_profile
vehicle_of_swarm(load_profile("sitl_quad"), 2, 2, "tcp/127.0.0.1:1", "bus")
print("vehicle", flush=True)
time.sleep(120)
"""
LAUNCHER = f"""
import os, subprocess, sys, time
env = {{**os.environ, {LAUNCHER_ENV!r}: str(os.getpid())}}
child = subprocess.Popen([sys.executable, "-c", {VEHICLE!r}], env=env)
print(child.pid, flush=True)
time.sleep(120)
"""


def test_a_vehicle_is_stopped_when_its_launcher_is_killed_outright() -> None:
    launcher = subprocess.Popen([sys.executable, "-c", LAUNCHER], stdout=subprocess.PIPE, text=True, cwd=REPO)
    assert launcher.stdout is not None
    vehicle = int(launcher.stdout.readline())
    try:
        assert launcher.stdout.readline().strip() == "vehicle"  # past vehicle_of_swarm: its guard armed
        launcher.kill()
        launcher.wait(10)
        deadline = time.monotonic() + 10
        while _alive(vehicle) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _alive(vehicle), "the vehicle outlived its launcher"
    finally:
        launcher.kill()
        if _alive(vehicle):
            os.kill(vehicle, signal.SIGKILL)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False
