"""CPU and memory of the default quad on the wall clock (``stack up --realtime``), as the modules share processes.

Run with ``python benchmarks/bench_realtime.py`` (``--runs N``, ``--profile NAME``). For each way of putting the
lockstep modules in processes (``own``: every module its own, as the default profile; ``inner``, ``two`` and
``one``: the groupings of ``benchmarks/bench_lockstep.py``), it starts ``stack up PROFILE --realtime`` in a
temporary ``STACK_HOME``, waits for every module to run, then samples all of the stack's processes (psutil): their
count, resident and unique memory, the CPU they take in ``--idle`` seconds on the ground (``--settle`` seconds after
the start), then, after ``stack cmd takeoff --alt 3 --wait`` and ``--settle`` seconds, in ``--hover`` seconds of the
hover. CPU is in cores (1.0: one core busy all the time); each figure is the highest over the runs, the kinds
interleaved.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import psutil
from bench_lockstep import GROUPINGS, grouped_profile, memory, module_processes

from stack.cli.common import print_table
from tests.support.harness import RunningStack

KINDS = ("own", *GROUPINGS)


def cores(procs: dict[str, psutil.Process], seconds: float) -> float:
    """The CPU the processes take over ``seconds`` of the wall clock, in cores."""
    before = {name: sum(p.cpu_times()[:2]) for name, p in procs.items()}
    time.sleep(seconds)
    return sum(sum(p.cpu_times()[:2]) - before[name] for name, p in procs.items()) / seconds


def measure(profile: str | Path, home: Path, args: argparse.Namespace) -> dict[str, float]:
    stack = RunningStack(home, profile, "--realtime", "--quiet")
    try:
        stack.wait_up()
        procs = module_processes(stack.proc.pid)
        counted = memory(procs)
        assert counted is not None, "a process of the stack ended"
        count, resident, unique = counted
        time.sleep(args.settle)
        idle = cores(procs, args.idle)
        takeoff = stack.cli("cmd", "takeoff", "--alt", "3", "--wait", timeout=90)
        assert "takeoff complete" in takeoff.stdout, takeoff.stdout + takeoff.stderr
        time.sleep(args.settle)
        hover = cores(procs, args.hover)
    finally:
        stack.stop()
    return {"processes": count, "resident": resident / 2**20, "unique": unique / 2**20, "idle": idle, "hover": hover}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--profile", default="sitl_quad")
    parser.add_argument("--idle", type=float, default=10.0)
    parser.add_argument("--settle", type=float, default=5.0)
    parser.add_argument("--hover", type=float, default=20.0)
    args = parser.parse_args()
    results: dict[str, list[dict[str, float]]] = {kind: [] for kind in KINDS}
    with tempfile.TemporaryDirectory(prefix="bench-realtime-") as tmp:
        work = Path(tmp)
        profiles = {kind: grouped_profile(args.profile, kind, work) for kind in GROUPINGS}
        for run in range(args.runs):
            for kind in KINDS:
                home = work / f"home-{kind}-{run}"
                results[kind].append(measure(profiles.get(kind, args.profile), home, args))
                print(f"run {run + 1} {kind}: {results[kind][-1]}", file=sys.stderr)
    rows = []
    for kind, runs in results.items():
        worst = {key: max(r[key] for r in runs) for key in runs[0]}
        rows.append(
            [
                kind,
                f"{worst['processes']:.0f}",
                f"{worst['resident']:.0f} MB",
                f"{worst['unique']:.0f} MB",
                f"{worst['idle']:.2f}",
                f"{worst['hover']:.2f}",
            ]
        )
    print(f"{args.profile} --realtime, highest of {args.runs} run(s); CPU in cores")
    print_table(["MODULES PER PROCESS", "PROCESSES", "RESIDENT", "UNIQUE", "IDLE CPU", "HOVER CPU"], rows)


if __name__ == "__main__":
    main()
