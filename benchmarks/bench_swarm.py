"""Swarm scale: real-time factor and memory per vehicle of `stack up --vehicles N` in lockstep, as fast as it goes.

Run with ``python benchmarks/bench_swarm.py`` (``--counts 1,2,4``: the swarm sizes; ``--duration``: wall seconds
measured in each run). For each layout (every module its own process, as the default profile has it; and each
vehicle's lockstep modules in one process, ``process = "vehicle"``) and each N, it starts ``stack up PROFILE
--vehicles N --speed max --quiet`` with a temporary ``STACK_HOME`` (never ``~/.stack``), waits until every
vehicle's modules are up, then follows the simulators' heartbeats (about 1 Hz of wall time, each with its simulated
time) for ``--duration`` seconds: a vehicle's real-time factor is the simulated time it gained between its first and
last beat of that window over the wall time between them. Memory is the resident and unique bytes of every process
of the swarm, per vehicle, read in the same window. A layout stops growing N once its slowest vehicle runs below
0.6x (twice as many vehicles could not keep real time) or the next N would need more memory than is available.

It prints a table per layout and the largest N whose slowest vehicle kept at least real time. The vehicles share
one world clock (stack.runtime.world_clock), so their factors agree within 50 ms: the slowest is the swarm's.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import msgspec
import psutil

from stack.bus import keys
from stack.bus.config import BusConfig
from stack.bus.node import open_session
from stack.msg.internal import ModuleHeartbeat
from stack.supervisor import state as run_state

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from bench_lockstep import grouped_profile  # noqa: E402  (beside this script)

from tests.support.harness import stack_env  # noqa: E402

LAYOUTS = {"per module": "one process per module", "per vehicle": "one process per vehicle (module groups)"}
SLOWEST_WORTH_GROWING = 0.6
UP_TIMEOUT_S = 60.0
UP_TIMEOUT_PER_VEHICLE_S = 20.0
STOP_TIMEOUT_S = 60.0
BEATS = keys.heartbeat_key("*", "simulator")
HEADER = f"{'N':>3} {'slowest':>8} {'mean':>6} {'fastest':>8} {'processes':>9} {'MB/vehicle':>10} {'unique':>7}"


@dataclass
class SwarmRun:
    vehicles: int
    factors: dict[str, float]  # vehicle → real-time factor
    processes: int
    rss: int
    uss: int

    @property
    def slowest(self) -> float:
        return min(self.factors.values())


def up_lines_seen(log: Path, count: int) -> bool:
    """Whether every vehicle said it is up (a swarm of one is a plain `stack up`, its lines not prefixed)."""
    text = log.read_text() if log.exists() else ""
    if count == 1:
        return re.search(r"(?m)^(v1: )?\[stack\] all \d+ modules up", text) is not None
    return all(re.search(rf"(?m)^v{i}: \[stack\] all \d+ modules up", text) for i in range(1, count + 1))


def swarm_memory(launcher: psutil.Process) -> tuple[int, int, int]:
    """How many processes the swarm has (the launcher, or the one vehicle's supervisor, and all below it), and
    their resident and unique bytes."""
    processes, rss, uss = 0, 0, 0
    for p in [launcher, *launcher.children(recursive=True)]:
        try:
            info = p.memory_full_info()
        except psutil.Error:
            continue
        processes, rss, uss = processes + 1, rss + info.rss, uss + info.uss
    return processes, rss, uss


def fly_swarm(profile: str, count: int, duration: float, home: Path) -> SwarmRun:
    log = home / f"swarm-{count}.out"
    env = stack_env(home)
    command = [sys.executable, "-m", "stack", "up", profile, "--vehicles", str(count), "--speed", "max", "--quiet"]
    with log.open("w") as out:
        proc = subprocess.Popen(command, env=env, stdout=out, stderr=subprocess.STDOUT, cwd=REPO)
    try:
        deadline = time.monotonic() + UP_TIMEOUT_S + UP_TIMEOUT_PER_VEHICLE_S * count
        while not up_lines_seen(log, count):
            if proc.poll() is not None or time.monotonic() > deadline:
                tail = "\n".join(log.read_text().splitlines()[-15:])
                raise SystemExit(f"a swarm of {count} did not come up:\n{tail}")
            time.sleep(0.2)
        endpoint = next(str(s["endpoint"]) for s in run_state.running_stacks() if s["vehicle"] == "v1")
        beats: dict[str, list[tuple[float, int]]] = {}
        decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
        session = open_session(BusConfig(mode="client", connect=(endpoint,), listen=()), f"bench-{os.getpid()}")
        try:
            sub = session.declare_subscriber(BEATS)
            end = time.monotonic() + duration
            memory = (0, 0, 0)
            while time.monotonic() < end:
                sample = sub.try_recv()
                if sample is None:
                    time.sleep(0.01)
                    continue
                vehicle = str(sample.key_expr).split("/")[1]
                beat = decoder.decode(sample.payload.to_bytes())
                beats.setdefault(vehicle, []).append((time.monotonic(), beat.sim_time_us))
                if memory[0] == 0 and len(beats) == count:
                    memory = swarm_memory(psutil.Process(proc.pid))
            sub.undeclare()
        finally:
            session.close()
    finally:
        stop_swarm(proc, count)
    factors = {}
    for vehicle, seen in beats.items():
        if len(seen) >= 2 and seen[-1][0] > seen[0][0]:
            factors[vehicle] = (seen[-1][1] - seen[0][1]) / 1e6 / (seen[-1][0] - seen[0][0])
    if len(factors) < count:
        raise SystemExit(f"a swarm of {count}: beats from {len(factors)} vehicles only; lengthen --duration")
    return SwarmRun(count, factors, *memory)


def stop_swarm(proc: subprocess.Popen, count: int) -> None:
    """Ctrl-C to the swarm, then wait until none of its stacks runs (a vehicle still stopping would refuse the next
    swarm's vehicle of its name); what still runs after STOP_TIMEOUT_S is killed, and said."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    deadline = time.monotonic() + STOP_TIMEOUT_S + count
    while (proc.poll() is None or run_state.running_stacks()) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = run_state.running_stacks()
    if proc.poll() is None or left:
        print(f"    (the swarm of {count} did not stop within {STOP_TIMEOUT_S + count:.0f} s: killed)", flush=True)
        pids = [proc.pid, *(int(s["pid"]) for s in left)]
        for pid in pids:
            try:
                tree = psutil.Process(pid)
                for p in [tree, *tree.children(recursive=True)]:
                    p.kill()
            except psutil.Error:
                continue
        proc.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="sitl_quad", help="launch profile (a name in launch/ or a path)")
    parser.add_argument("--counts", default="1,2,4,8,16,32", help="swarm sizes, in growing order")
    parser.add_argument("--duration", type=float, default=12.0, help="wall seconds measured in each run")
    parser.add_argument("--layouts", default=",".join(LAYOUTS), help="layouts measured: " + ", ".join(LAYOUTS))
    args = parser.parse_args()
    counts = [int(c) for c in args.counts.split(",")]
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs; profile {args.profile}")
    best: dict[str, int] = {}
    with tempfile.TemporaryDirectory(prefix="bench_swarm") as tmp:
        home = Path(tmp)
        os.environ["STACK_HOME"] = str(home)  # where run_state finds the swarm's stacks
        profiles = {"per module": args.profile, "per vehicle": str(grouped_profile(args.profile, "one", home))}
        for layout in args.layouts.split(","):
            print(f"\n{LAYOUTS[layout]}")
            print(HEADER)
            for count in counts:
                run = fly_swarm(profiles[layout], count, args.duration, home)
                mean = sum(run.factors.values()) / count
                print(
                    f"{count:>3} {run.slowest:>8.2f} {mean:>6.2f} {max(run.factors.values()):>8.2f} {run.processes:>9}"
                    f" {run.rss / count / 2**20:>10.0f} {run.uss / count / 2**20:>7.0f}",
                    flush=True,
                )
                if run.slowest >= 1.0:
                    best[layout] = count
                following = next((c for c in counts if c > count), None)
                needed = run.uss / count * (following or 0)
                if run.slowest < SLOWEST_WORTH_GROWING or needed > psutil.virtual_memory().available:
                    if following is not None:
                        print(f"    (not growing past {count}: slowest {run.slowest:.2f}x, or memory)")
                    break
    print("\nthe largest swarm whose slowest vehicle kept real time (>= 1x):")
    for layout in args.layouts.split(","):
        print(f"  {layout:<12} {best.get(layout, 0)} vehicles")


if __name__ == "__main__":
    main()
