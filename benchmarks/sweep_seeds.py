"""Fly one scenario over many seeds, several at once, and report every check per seed and the worst of each.

    python benchmarks/sweep_seeds.py --scenario takeoff_land --seeds 1-20 --jobs 2 [--profile P] [--wind]

Each seed is one ``stack fly SCENARIO --seed N --quiet`` in a fresh interpreter. A flight is a stack of
its own (its bus, ports, run directory and state), so ``--jobs`` of them run side by side in one
``STACK_HOME``: a temporary one, or ``--home DIR`` to keep every run directory, report and output.

A figure holds only if it holds on every seed, so for each check the summary gives the worst value over
the seeds (the highest against an upper limit, the lowest against a lower one, a wrong one against an
exact one), its seed, and on how many seeds the check passed. A seed whose flight left no report fails
every check. The exit code is 0 only if every seed passed.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from stack.cli.common import format_value, print_table
from stack.scenario.catalogue import Check, scenarios
from stack.supervisor.profile import DEFAULT_PROFILE

FLY_TIMEOUT_S = 1800.0


def parse_seeds(text: str) -> list[int]:
    """``1-20``, ``3``, or a comma-separated mix such as ``1,4,10-12``."""
    seeds: list[int] = []
    for part in text.split(","):
        first, _, last = part.strip().partition("-")
        seeds.extend(range(int(first), int(last or first) + 1))
    if not seeds or len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"'{text}': expected distinct seeds such as 1-20 or 1,4,10-12")
    return seeds


def fly(scenario: str, profile: str, seed: int, wind: bool, home: Path) -> dict[str, Any]:
    """One ``stack fly``; its report, or ``{"seed", "passed": False, "error"}`` when it left none."""
    report, log = home / f"report-{seed}.json", home / f"seed-{seed}.out"
    env = {k: v for k, v in os.environ.items() if k != "STACK_ENDPOINT"}
    env.update(STACK_HOME=str(home), PYTHONUNBUFFERED="1")
    args = ["fly", scenario, "--profile", profile, "--seed", str(seed), "--quiet", "--report", str(report)]
    with log.open("w") as out:
        try:
            code = subprocess.run(
                [sys.executable, "-m", "stack", *args, *(["--wind"] if wind else [])],
                env=env,
                stdout=out,
                stderr=subprocess.STDOUT,
                timeout=FLY_TIMEOUT_S,
            ).returncode
        except subprocess.TimeoutExpired:
            code = None
    if not report.exists():
        how = f"exit code {code}" if code is not None else f"no result within {FLY_TIMEOUT_S:g} s"
        tail = " | ".join(log.read_text().splitlines()[-3:])
        return {"seed": seed, "passed": False, "error": f"no report, {how}: {tail}"}
    return json.loads(report.read_text())


def worst(check: Check, found: list[tuple[int, Any]]) -> tuple[int, Any]:
    """The (seed, value) furthest on the failing side of ``check``; a missing or NaN value is the worst."""
    if isinstance(check.limit, bool | str):
        return next((f for f in found if f[1] != check.limit), found[0])
    missing = [f for f in found if not isinstance(f[1], int | float) or f[1] != f[1]]
    if missing:
        return missing[0]
    return (min if check.at_least else max)(found, key=lambda f: f[1])


def print_seeds(checks: tuple[Check, ...], reports: list[dict[str, Any]]) -> None:
    rows = []
    for r in reports:
        by_name = {c["name"]: c for c in r.get("checks", [])}
        cells = []
        for check in checks:
            c = by_name.get(check.metric)
            cells.append("-" if c is None else format_value(c["value"]) + ("" if c["passed"] else "*"))
        rows.append((r["seed"], *cells, "passed" if r["passed"] else "FAILED"))
    print_table(("SEED", *(c.metric for c in checks), "RESULT"), rows)
    if any(not c["passed"] for r in reports for c in r.get("checks", [])):
        print("(* fails its limit)")


def print_worst(checks: tuple[Check, ...], reports: list[dict[str, Any]]) -> None:
    rows = []
    for check in checks:
        found = [(r["seed"], c) for r in reports for c in r.get("checks", []) if c["name"] == check.metric]
        passed = sum(1 for _, c in found if c["passed"])
        seed, value = worst(check, [(s, c["value"]) for s, c in found]) if found else ("-", "-")
        limit = found[0][1]["limit"] if found else check.limit
        side = "==" if isinstance(limit, bool | str) else ">=" if check.at_least else "<="
        rows.append(
            (check.metric, f"{side} {format_value(limit)}", format_value(value), seed, f"{passed}/{len(reports)}")
        )
    print_table(("CHECK", "LIMIT", "WORST", "SEED", "PASSED"), rows)


def sweep(args: argparse.Namespace, home: Path) -> int:
    checks = scenarios()[args.scenario].checks
    wind = ", in wind" if args.wind else ""
    print(f"{args.scenario} on {args.profile}{wind}: {len(args.seeds)} seeds, {args.jobs} at a time, STACK_HOME {home}")
    start = time.monotonic()
    reports = []
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(fly, args.scenario, args.profile, s, args.wind, home) for s in args.seeds]
        for future in as_completed(futures):
            r = future.result()
            reports.append(r)
            detail = r["error"] or f"{r['wall_time_s']:.0f} s, real-time factor {r['realtime_factor']:.1f}"
            print(f"seed {r['seed']}: {'passed' if r['passed'] else 'FAILED'} ({detail})", flush=True)
    reports.sort(key=lambda r: r["seed"])
    print()
    print_seeds(checks, reports)
    print()
    print_worst(checks, reports)
    passed = sum(1 for r in reports if r["passed"])
    elapsed = time.monotonic() - start
    print(f"\n{passed}/{len(reports)} seeds passed in {elapsed:.0f} s; a figure holds only if it holds on every seed")
    return 0 if passed == len(reports) else 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", required=True, choices=sorted(scenarios()), help="the scenario to fly")
    parser.add_argument("--seeds", type=parse_seeds, default="1-10", help="e.g. 1-20 or 1,4,10-12")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="flights at once (default: one per CPU)")
    parser.add_argument("--profile", default=DEFAULT_PROFILE, help="launch profile (a name in launch/ or a path)")
    parser.add_argument("--wind", action="store_true", help="fly in wind (`stack fly --wind`: the limits doubled)")
    parser.add_argument("--home", type=Path, help="STACK_HOME to keep the runs, reports and outputs in")
    args = parser.parse_args()
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    if args.home is not None:
        args.home.mkdir(parents=True, exist_ok=True)
        raise SystemExit(sweep(args, args.home.resolve()))
    with tempfile.TemporaryDirectory(prefix="sweep_seeds-") as tmp:
        code = sweep(args, Path(tmp))
    raise SystemExit(code)


if __name__ == "__main__":
    main()
