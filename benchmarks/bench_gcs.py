"""What the ``mavlink`` module costs, and how fast it answers a command.

Run with ``python benchmarks/bench_gcs.py`` (``--realtime`` paces the simulator to the wall clock instead of
lockstep; ``--window`` seconds per measurement; ``--commands`` per latency series). Each stack runs in a
temporary ``STACK_HOME`` through the real CLI, its links on free 127.0.0.1 ports:

- **baseline**: the default profile without its two links: the simulation's real-time factor (in lockstep);
- **idle**: the default profile, nobody on the links: each link process's CPU (psutil, % of one core) and the
  real-time factor, i.e. what an unused link costs the stack;
- **connected**: a ground station (pymavlink, 1 Hz heartbeat, receiving PX4's normal-mode streams) on the
  GCS link: that link's CPU, the whole stack's CPU, and the real-time factor;
- **command → ACK**: ``--commands`` COMMAND_LONGs one after the other, timed from the send to the COMMAND_ACK
  at the ground station, p50 and p99: DO_SET_MODE to Hold (through the commander and back) and
  REQUEST_MESSAGE (answered by the link itself).

Figures are printed, not asserted; the load average the runs began with is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

import psutil
from pymavlink.dialects.v20 import common as mavlink2

from tests.mavlink.peer import Link, Peer, links_profile, udp_port
from tests.support.harness import REPO, RunningStack, toml_text, write_profile

SETTLE_S = 6.0
"""After start-up, and after a ground station connects (its telemetry topics are subscribed to)."""


def _status(stack: RunningStack) -> dict:
    return {m["module"]: m for m in stack.status()["modules"]}


def _sim_time_us(stack: RunningStack) -> int:
    return max(m.get("sim_time_us", 0) for m in _status(stack).values())


def measure(stack: RunningStack, window_s: float) -> tuple[dict[str, float], float]:
    """Each module process's CPU (% of one core) and the real-time factor over ``window_s``."""
    procs = {name: psutil.Process(m["pid"]) for name, m in _status(stack).items() if m["pid"]}
    before = {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
    sim0, wall0 = _sim_time_us(stack), time.monotonic()
    time.sleep(window_s)
    wall = time.monotonic() - wall0
    rtf = (_sim_time_us(stack) - sim0) / 1e6 / wall
    cpu = {name: 100.0 * (sum(p.cpu_times()[:2]) - before[name]) / wall for name, p in procs.items()}
    return cpu, rtf


def latencies(peer: Peer, command: int, params: tuple[float, ...], count: int) -> list[float]:
    """Each command is sent a random 0–20 ms after the previous answer, so that it meets the commander's 100 Hz
    cycle at any phase (sent at once, it would always wait a whole cycle)."""
    out = []
    for _ in range(count):
        time.sleep(random.uniform(0.0, 0.02))
        t0 = time.monotonic()
        ack = peer.command(command, *params)
        out.append((time.monotonic() - t0) * 1000.0)
        assert ack.result == mavlink2.MAV_RESULT_ACCEPTED, ack
    return out


def percentiles(values: list[float]) -> str:
    q = statistics.quantiles(values, n=100)
    return f"p50 {statistics.median(values):.1f} ms, p99 {q[98]:.1f} ms, max {max(values):.1f} ms"


def without_links(path: Path) -> Path:
    doc = tomllib.loads((REPO / "launch" / "sitl_quad.toml").read_text())
    doc["module"] = [m for m in doc["module"] if m["module"] != "mavlink"]
    return write_profile(path, toml_text(doc))


def start(home: Path, profile: Path, realtime: bool) -> RunningStack:
    stack = RunningStack(home, profile, "--quiet", *(["--realtime"] if realtime else []))
    stack.wait_up(180)
    time.sleep(SETTLE_S)
    return stack


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--realtime", action="store_true", help="simulator paced to the wall clock (no lockstep)")
    parser.add_argument("--window", type=float, default=10.0, help="seconds per CPU measurement")
    parser.add_argument("--commands", type=int, default=200, help="commands per latency series")
    args = parser.parse_args()
    print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    kind = "real time" if args.realtime else "lockstep"
    with tempfile.TemporaryDirectory(prefix="bench-gcs-") as tmp:
        home = Path(tmp)
        baseline = start(home, without_links(home / "baseline.toml"), args.realtime)
        try:
            _, rtf_baseline = measure(baseline, args.window)
        finally:
            baseline.stop()
        gcs = Link("mavlink_gcs", udp_port(), udp_port())
        stack = start(home, links_profile(home / "links.toml", [gcs]), args.realtime)
        try:
            idle, rtf_idle = measure(stack, args.window)
            peer = Peer(gcs.remote)
            try:
                peer.connect()
                time.sleep(SETTLE_S)
                connected, rtf_connected = measure(stack, args.window)
                mode = latencies(peer, mavlink2.MAV_CMD_DO_SET_MODE, (1, 4, 3), args.commands)
                local = latencies(
                    peer, mavlink2.MAV_CMD_REQUEST_MESSAGE, (mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION,), args.commands
                )
                extra = _status(stack)["mavlink_gcs"]["extra"]
            finally:
                peer.close()
        finally:
            stack.stop()
    print(f"\n{kind}, default profile (two links: mavlink_gcs, mavlink_api)")
    if not args.realtime:
        print(
            f"  real-time factor: without links {rtf_baseline:.2f}, links idle {rtf_idle:.2f}, "
            f"GCS connected {rtf_connected:.2f}"
        )
    print(f"  link CPU idle: mavlink_gcs {idle['mavlink_gcs']:.1f} %, mavlink_api {idle['mavlink_api']:.1f} %")
    print(f"  link CPU with a ground station: mavlink_gcs {connected['mavlink_gcs']:.1f} %")
    others = sum(v for k, v in connected.items() if not k.startswith("mavlink")) - sum(
        v for k, v in idle.items() if not k.startswith("mavlink")
    )
    print(f"  the other modules' CPU with a ground station: {others:+.1f} % (all modules together)")
    print(f"  streamed: {extra['packets_out']} packets, {extra['bytes_out']} bytes out so far")
    print(f"  command → ACK, DO_SET_MODE through the commander: {percentiles(mode)}")
    print(f"  command → ACK, REQUEST_MESSAGE answered by the link: {percentiles(local)}")
    print(json.dumps({"rtf": [rtf_baseline, rtf_idle, rtf_connected], "cpu_idle": idle, "cpu_connected": connected}))


if __name__ == "__main__":
    main()
