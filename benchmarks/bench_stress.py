"""The lockstep under CPU contention: flights and an idle stack while other processes keep every core busy.

    python benchmarks/bench_stress.py [--burners 4] [--flights 30] [--idle-minutes 30] [--scenario takeoff_land]

Starts ``--burners`` CPU-burning processes (a Python busy loop each, at normal priority) and keeps them
running throughout. Then:

1. flies ``--flights`` ``stack fly SCENARIO --seed N`` (seeds 1..N, ``--jobs`` at a time), each in a fresh
   interpreter as ``benchmarks/sweep.py`` does. A flight that left no report (the stack stopped:
   a stall, a crash) or whose output names a lockstep stall counts as a stall; a flight that finished
   but failed a check is counted apart, since a loaded machine must only make a flight slower.
2. runs ``stack up`` (disarmed) for ``--idle-minutes`` and follows the lockstep coordinator's heartbeat:
   a stall is the stack exiting before its time, or simulated time not advancing for ``STALL_WALL_S``.

It prints each flight and, every minute of the idle run, the simulated time and real-time factor; then
the load average, stalls and the slowest real-time factors seen. Exit code 0 only with no stall.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import msgspec
from sweep import fly

from stack.bus import keys
from stack.cli.common import connect
from stack.msg.internal import ModuleHeartbeat
from stack.supervisor import state as run_state
from stack.supervisor.profile import DEFAULT_PROFILE

REPO = Path(__file__).resolve().parents[1]
STALL_WALL_S = 60.0
STALL_WORDS = ("lockstep stalled",)


def start_burners(count: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]


def stalled_in(log: Path) -> str:
    text = log.read_text(errors="replace") if log.exists() else ""
    return next((line for line in text.splitlines() if any(w in line for w in STALL_WORDS)), "")


def flights(args: argparse.Namespace, home: Path) -> tuple[int, int]:
    stalls = failed = 0
    print(f"{args.flights} flights of {args.scenario}, {args.jobs} at a time", flush=True)
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        reports = pool.map(lambda s: fly(args.scenario, args.profile, s, False, home), range(1, args.flights + 1))
        for r in reports:
            seed = r["seed"]
            stall = r.get("error") or stalled_in(Path(r["log"]))
            if stall:
                stalls += 1
                print(f"seed {seed}: STALL: {stall}", flush=True)
                continue
            failed += not r["passed"]
            verdict = "passed" if r["passed"] else "finished, failed a check"
            print(
                f"seed {seed}: {verdict} ({r['wall_time_s']:.0f} s, real-time factor {r['realtime_factor']:.2f})",
                flush=True,
            )
    return stalls, failed


def idle(args: argparse.Namespace, home: Path) -> int:
    duration = args.idle_minutes * 60.0
    log = home / "up.out"
    env = {k: v for k, v in os.environ.items() if k != "STACK_ENDPOINT"}
    print(f"`stack up {args.profile}` idle for {args.idle_minutes:g} min", flush=True)
    with log.open("w") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "stack", "up", args.profile, "--speed", "max", "--duration", str(duration)],
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
            cwd=REPO,
        )
    try:
        stall = follow(proc, duration)
        proc.wait(timeout=120.0)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    stall = stall or stalled_in(log) or (f"`stack up` exited with {proc.returncode}" if proc.returncode else "")
    if stall:
        print(f"idle stack: STALL: {stall}", flush=True)
        return 1
    print("idle stack: no stall", flush=True)
    return 0


def follow(proc: subprocess.Popen, duration: float) -> str:
    """Simulated time from the coordinator's heartbeats until the stack ends; what went wrong, if anything."""
    start = time.monotonic()
    while not (state := next((s for s in run_state.running_stacks() if s["pid"] == proc.pid), None)):
        if proc.poll() is not None or time.monotonic() - start > 120.0:
            return "the stack did not come up"
        time.sleep(0.1)
    decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
    sim_us, progressed, last_print, first = 0, time.monotonic(), time.monotonic(), None
    with connect(run_state.stack_name(state), None, name="stress") as node:
        sub = node.session.declare_subscriber(keys.heartbeat_all(node.vehicle))
        try:
            while proc.poll() is None:
                now = time.monotonic()
                if now - progressed > STALL_WALL_S:
                    return f"simulated time stuck at {sim_us / 1e6:.3f} s for {STALL_WALL_S:g} s"
                sample = sub.try_recv()
                if sample is None:
                    time.sleep(0.05)
                    continue
                hb = decoder.decode(sample.payload.to_bytes())
                if hb.trigger != "lockstep coordinator":
                    continue
                if hb.sim_time_us > sim_us:
                    sim_us, progressed = hb.sim_time_us, now
                    first = first or (now, sim_us)
                if now - last_print >= 60.0 and first:
                    rtf = (sim_us - first[1]) / 1e6 / max(now - first[0], 1e-9)
                    print(f"  {now - start:5.0f} s wall: simulated {sim_us / 1e6:8.1f} s, real-time factor {rtf:.2f}")
                    last_print = now
        finally:
            sub.undeclare()
    if time.monotonic() - start < duration - 5.0:
        return f"the stack ended after {time.monotonic() - start:.0f} s of {duration:.0f}"
    return ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--burners", type=int, default=4, help="CPU-burning processes kept running")
    parser.add_argument("--flights", type=int, default=30, help="flights, seeds 1..N (0: none)")
    parser.add_argument("--jobs", type=int, default=1, help="flights at once")
    parser.add_argument("--idle-minutes", type=float, default=30.0, help="minutes of idle `stack up` (0: none)")
    parser.add_argument("--scenario", default="takeoff_land", help="the scenario flown")
    parser.add_argument("--profile", default=DEFAULT_PROFILE, help="launch profile (a name in launch/ or a path)")
    parser.add_argument("--home", type=Path, help="STACK_HOME to keep the runs and outputs in")
    args = parser.parse_args()
    burners = start_burners(args.burners)
    try:
        with tempfile.TemporaryDirectory(prefix="stack-stress-") as tmp:
            home = args.home or Path(tmp)
            home.mkdir(parents=True, exist_ok=True)
            os.environ["STACK_HOME"] = str(home)  # this script finds the idle stack's state there too
            print(f"{args.burners} CPU burners on {os.cpu_count()} CPUs; STACK_HOME {home}", flush=True)
            stalls, failed = flights(args, home) if args.flights else (0, 0)
            idle_stalls = idle(args, home) if args.idle_minutes else 0
            load = " ".join(f"{x:.2f}" for x in os.getloadavg())
            print(
                f"\nload average {load}; flights: {stalls} stall(s), {failed} finished with a failed check, "
                f"of {args.flights}; idle stack: {idle_stalls} stall(s)"
            )
    finally:
        for b in burners:
            b.kill()
            b.wait()
    sys.exit(1 if stalls or idle_stalls else 0)


if __name__ == "__main__":
    main()
