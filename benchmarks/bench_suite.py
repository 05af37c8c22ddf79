"""Where the test suite's CPU goes: every Python process it starts, counted by what it is, as it ends.

Run with ``python benchmarks/bench_suite.py`` (the suite as the README runs it, about 25 minutes on the 2-core
machine), or give pytest's arguments after ``--`` (``python benchmarks/bench_suite.py -- tests/cli -n 2``). It puts
a ``sitecustomize`` of its own on ``PYTHONPATH`` (the tests' commands keep it: tests/support/harness.py's
``stack_env`` adds the repository in front of it), so every interpreter the suite starts, test workers, supervisors,
module processes and CLI commands, writes its CPU (user + system, all its threads) to one log when it exits. The
table sums them by kind:

- ``test workers``: pytest's workers (unit tests, in-process flights) and the main pytest process;
- ``module NAME``: one module process (``stack.runtime.main``, a process group's name for modules sharing one);
- ``stack up`` / ``stack fly``: supervisors; ``stack pixhawk-sim``: the simulated Pixhawk;
- ``cli …``: every other ``stack`` command (a test's ``stack status``, ``stack topic echo``…);
- ``other python``: interpreters started otherwise (``python -c``, MAVSDK's helpers…).

A process ended by a signal it does not handle (SIGKILL: a test's killed module, the orphan tests) never writes
its line; the machine's busy CPU over the run (psutil's ``cpu_times``) shows how much was counted. An environment with a
``sitecustomize`` of its own loses it for the run.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import psutil

from stack.cli.common import print_table

REPO = Path(__file__).resolve().parent.parent
LOG_ENV = "STACK_BENCH_SUITE_LOG"
HOOK = """
import atexit, os, sys

_argv = list(getattr(sys, "orig_argv", ()))


def _bench_suite_log():
    t = os.times()
    line = "%s\\t%.3f\\n" % ("\\x1f".join(_argv), t.user + t.system)
    fd = os.open(os.environ["{log}"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
    try:
        os.write(fd, line.encode())
    finally:
        os.close(fd)


if os.environ.get("{log}"):
    atexit.register(_bench_suite_log)
""".replace("{log}", LOG_ENV)


def kind(argv: list[str]) -> str:
    """What an interpreter was, from its command line (``sys.orig_argv``)."""
    if "-m" not in argv:
        return "test workers" if any("exec(eval(sys.stdin.readline()))" in a for a in argv) else "other python"
    i = argv.index("-m")
    module, rest = (argv[i + 1] if i + 1 < len(argv) else ""), argv[i + 2 :]
    if module == "pytest":
        return "test workers"
    if module == "stack.runtime.main":
        spec = Path(rest[-1]).name if rest else "?"
        return "module " + spec.removesuffix(".json").removesuffix(".spec")
    if module != "stack":
        return "other python"
    words = [a for a in rest if not a.startswith("-")]
    if not words:
        return "cli"
    if words[0] in ("up", "fly", "pixhawk-sim", "router", "teleop", "plot"):
        return f"stack {words[0]}"
    if words[0] in ("topic", "param", "cmd", "log", "keys", "mavlink") and len(words) > 1:
        return f"cli {words[0]} {words[1]}"
    return f"cli {words[0]}"


def busy_seconds() -> float:
    """The machine's CPU time spent on anything but idle and I/O wait since boot, in seconds."""
    t = psutil.cpu_times()
    return t.user + t.nice + t.system + t.irq + t.softirq + t.steal


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--top", type=int, default=30, help="Rows of the table (the rest summed in one)")
    parser.add_argument("pytest_args", nargs="*", help="pytest's arguments, after --")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-suite-") as tmp:
        hook = Path(tmp) / "hook"
        hook.mkdir()
        (hook / "sitecustomize.py").write_text(HOOK)
        log = Path(tmp) / "processes.log"
        env = {**os.environ, LOG_ENV: str(log)}
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(hook), str(REPO), os.environ.get("PYTHONPATH")) if p)
        busy, start = busy_seconds(), time.monotonic()
        code = subprocess.run([sys.executable, "-m", "pytest", *args.pytest_args], cwd=REPO, env=env).returncode
        wall, busy = time.monotonic() - start, busy_seconds() - busy
        lines = log.read_text().splitlines() if log.exists() else []
    cpu: dict[str, float] = defaultdict(float)
    count: dict[str, int] = defaultdict(int)
    for line in lines:
        argv, seconds = line.split("\t")
        k = kind(argv.split("\x1f"))
        cpu[k] += float(seconds)
        count[k] += 1
    total = max(sum(cpu.values()), 1e-9)

    def row(name: str, kinds: list[str]) -> tuple[object, ...]:
        seconds, processes = sum(cpu[k] for k in kinds), sum(count[k] for k in kinds)
        return name, processes, f"{seconds:.0f}", f"{100 * seconds / total:.1f}", f"{seconds / max(processes, 1):.2f}"

    ranked = sorted(cpu, key=lambda k: -cpu[k])
    rows = [row(k, [k]) for k in ranked[: args.top]]
    if ranked[args.top :]:
        rows.append(row(f"{len(ranked) - args.top} more kinds", ranked[args.top :]))
    rows.append(row("(module processes together)", [k for k in ranked if k.startswith("module ")]))
    print(f"\npytest exited {code} after {wall:.0f} s; the machine was busy {busy:.0f} CPU-s "
          f"({busy / wall / (os.cpu_count() or 1):.0%} of its {os.cpu_count()} cores), "
          f"{total:.0f} of them counted in {len(lines)} Python processes ({total / max(busy, 1e-9):.0%}):")  # fmt: skip
    print_table(("KIND", "PROCESSES", "CPU s", "%", "CPU s EACH"), rows)
    sys.exit(code)


if __name__ == "__main__":
    main()
