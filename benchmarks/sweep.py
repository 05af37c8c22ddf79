"""Fly every scenario over many seeds, calm and in wind, side by side, and judge each metric's worst seed.

    python benchmarks/sweep.py [--scenarios takeoff_land,mission_box] [--seeds 1-20] [--jobs 2]
                               [--profile P] [--wind both|calm|wind] [--wind-speed 8] [--per-seed]
                               [--vehicles 3] [--summary out.md|out.json]

Each flight is one ``stack fly SCENARIO --seed N --quiet [--wind]`` in a fresh interpreter; with
``--in-process`` it is the same flight, message for message, flown by ``stack.scenario.inprocess`` in a worker
process of its own (every module in one interpreter, no bus): about three times less CPU, so a 20-seed sweep
of the quadrotor's scenarios takes minutes, not an hour. module_kill (it kills module processes) and link_loss
(its simulated Pixhawk runs on the wall clock) fly only as ``stack fly``, and so do the swarm scenarios, with
``--vehicles`` vehicles (default 3), judged by their swarm's checks. A flight is a
stack of its own (its bus, ports, run directory and state), so ``--jobs`` of them run side by side in one
``STACK_HOME``: a temporary one, or ``--home DIR`` to keep every run directory, report and output. Without
``--profile`` a scenario flies on its own profile (``Scenario.profile``: link_loss on the simulated Pixhawk,
the plane's scenarios on sitl_plane) or the default one; in wind only where its profile simulates wind.

A figure holds only if it holds on every seed, so for each scenario (and condition) and each check the
summary gives the median and the worst value over the seeds (the highest against an upper limit, the lowest
against a lower one, a wrong one against an exact one) with the worst seed, against the limit the flight
was judged by (``--wind`` doubles the numeric ones), and on how many seeds the check passed. A flight that
left no report fails every check. The exit code is 0 only if every worst value meets its limit.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stack.cli.common import format_value, print_table
from stack.scenario.catalogue import Check, Scenario, scenarios
from stack.scenario.flight import WIND_PARAMS, WIND_SPEED
from stack.scenario.inprocess import fly_in_process
from stack.supervisor.profile import DEFAULT_PROFILE, load_profile

FLY_TIMEOUT_S = 1800.0
PROCESSES_ONLY = {
    "module_kill": "it kills module processes",
    "link_loss": "its simulated Pixhawk is a process on the wall clock",
    "swarm_formation": "its vehicles are stacks of their own on one bus",
    "swarm_leader_loss": "its vehicles are stacks of their own on one bus",
}
DEFAULT_VEHICLES = 3
CONDITIONS = {"both": (False, True), "calm": (False,), "wind": (True,)}


@dataclass(frozen=True)
class Case:
    """One scenario on one profile, calm or in wind."""

    scenario: Scenario
    profile: str
    wind: bool

    @property
    def name(self) -> str:
        return self.scenario.name + (" (wind)" if self.wind else "")


def parse_seeds(text: str) -> list[int]:
    """``1-20``, ``3``, or a comma-separated mix such as ``1,4,10-12``."""
    seeds: list[int] = []
    for part in text.split(","):
        first, _, last = part.strip().partition("-")
        seeds.extend(range(int(first), int(last or first) + 1))
    if not seeds or len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"'{text}': expected distinct seeds such as 1-20 or 1,4,10-12")
    return seeds


def fly(
    scenario: str, profile: str, seed: int, wind: bool, home: Path, wind_speed: float | None, vehicles: int = 1
) -> dict[str, Any]:
    """One ``stack fly``; its report (with ``log``, the flight's output), or ``{"seed", "passed": False,
    "error", "log"}`` when it left none."""
    stem = f"{scenario}{'-wind' if wind else ''}-seed{seed}"
    report, log = home / f"{stem}.json", home / f"{stem}.out"
    env = {k: v for k, v in os.environ.items() if k != "STACK_ENDPOINT"}
    env.update(STACK_HOME=str(home), PYTHONUNBUFFERED="1")
    args = ["fly", scenario, "--profile", profile, "--seed", str(seed), "--quiet", "--report", str(report)]
    args += ["--vehicles", str(vehicles)] if scenarios()[scenario].swarm is not None else []
    with log.open("w") as out:
        try:
            code = subprocess.run(
                [sys.executable, "-m", "stack", *args, *(_wind_args(wind_speed) if wind else [])],
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
        return {"seed": seed, "passed": False, "error": f"no report, {how}: {tail}", "log": str(log)}
    return json.loads(report.read_text()) | {"log": str(log)}


def fly_in_one_process(scenario: str, profile: str, seed: int, wind: bool, wind_speed: float | None) -> dict[str, Any]:
    """The flight of :func:`fly`, flown by ``stack.scenario.inprocess`` in this (worker) process."""
    try:
        speed = WIND_SPEED if wind_speed is None else wind_speed
        flight = fly_in_process(scenario, profile, seed, wind=wind, wind_speed=speed)
    except Exception as e:  # a flight that cannot run is a failed seed, not a failed sweep
        return {"seed": seed, "passed": False, "error": f"in-process flight failed: {type(e).__name__}: {e}"}
    return flight.result | {"seed": seed}


def _wind_args(wind_speed: float | None) -> list[str]:
    return ["--wind"] if wind_speed is None else ["--wind-speed", f"{wind_speed:g}"]


def simulates_wind(profile: str) -> bool:
    prof = load_profile(profile)
    return all(any(p.name == name for m in prof.modules for p in m.cls.PARAMS) for name in WIND_PARAMS)


def cases(names: list[str], profile: str | None, conditions: tuple[bool, ...]) -> list[Case]:
    known = scenarios()
    out = []
    for name in names:
        scenario = known[name]
        on = profile or scenario.profile or DEFAULT_PROFILE
        out.extend(Case(scenario, on, wind) for wind in conditions if not wind or simulates_wind(on))
    return out


def worst(check: Check, found: list[tuple[int, Any]]) -> tuple[int, Any]:
    """The (seed, value) furthest on the failing side of ``check``; a missing or NaN value is the worst."""
    if isinstance(check.limit, bool | str):
        return next((f for f in found if f[1] != check.limit), found[0])
    missing = [f for f in found if not isinstance(f[1], int | float) or f[1] != f[1]]
    if missing:
        return missing[0]
    return (min if check.at_least else max)(found, key=lambda f: f[1])


def median(check: Check, values: list[Any]) -> Any:
    """The median of a numeric check's values (NaN when one is missing); the most common value otherwise."""
    if isinstance(check.limit, bool | str):
        return statistics.mode(values)
    if any(not isinstance(v, int | float) or v != v for v in values):
        return float("nan")
    return statistics.median(values)


def checks_of(scenario: Scenario) -> tuple[Check, ...]:
    """What a flight of the scenario is judged by: a swarm's checks for a swarm scenario."""
    return scenario.swarm.checks if scenario.swarm is not None else scenario.checks


def summarise(case: Case, reports: list[dict[str, Any]]) -> dict[str, Any]:
    """Per check: limit, median, worst and its seed, seeds passed; ``passed`` when every worst meets its limit."""
    rows = []
    for check in checks_of(case.scenario):
        found = {r["seed"]: c for r in reports for c in r.get("checks", []) if c["name"] == check.metric}
        # A flight without a report fails every check.
        values = [(r["seed"], found[r["seed"]]["value"] if r["seed"] in found else None) for r in reports]
        seed, value = worst(check, values)
        limit = next(iter(found.values()))["limit"] if found else check.limit
        judged = Check(check.metric, limit, check.at_least)
        rows.append(
            {
                "check": check.metric,
                "limit": limit,
                "at_least": check.at_least,
                "median": median(check, [v for _, v in values]),
                "worst": value,
                "worst_seed": seed,
                "passed_seeds": sum(1 for _, v in values if judged.passed(v)),
                "passed": judged.passed(value),
            }
        )
    return {
        "scenario": case.scenario.name,
        "profile": case.profile,
        "wind": case.wind,
        "seeds": [r["seed"] for r in reports],
        "errors": {r["seed"]: r["error"] for r in reports if r.get("error")},
        "checks": rows,
        "passed": all(row["passed"] for row in rows),
    }


def label(summary: dict[str, Any]) -> str:
    return summary["scenario"] + (" (wind)" if summary["wind"] else "")


def side(row: dict[str, Any]) -> str:
    return "==" if isinstance(row["limit"], bool | str) else ">=" if row["at_least"] else "<="


def print_seeds(case: Case, reports: list[dict[str, Any]]) -> None:
    rows = []
    for r in reports:
        by_name = {c["name"]: c for c in r.get("checks", [])}
        cells = []
        for check in checks_of(case.scenario):
            c = by_name.get(check.metric)
            cells.append("-" if c is None else format_value(c["value"]) + ("" if c["passed"] else "*"))
        rows.append((r["seed"], *cells, "passed" if r["passed"] else "FAILED"))
    print_table(("SEED", *(c.metric for c in checks_of(case.scenario)), "RESULT"), rows)


def print_summary(summary: dict[str, Any]) -> None:
    rows = [
        (
            row["check"],
            f"{side(row)} {format_value(row['limit'])}",
            format_value(row["median"]),
            format_value(row["worst"]),
            row["worst_seed"],
            f"{row['passed_seeds']}/{len(summary['seeds'])}",
            "ok" if row["passed"] else "FAIL",
        )
        for row in summary["checks"]
    ]
    print_table(("CHECK", "LIMIT", "MEDIAN", "WORST", "SEED", "PASSED", ""), rows)
    for seed, error in summary["errors"].items():
        print(f"seed {seed}: {error}")


def markdown(summaries: list[dict[str, Any]], seeds: list[int]) -> str:
    lines = [
        f"Seeds {seeds[0]}–{seeds[-1]} ({len(seeds)}); in wind the numeric limits are doubled.",
        "",
        "| scenario | check | limit | median | worst (seed) | seeds passed |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for s in summaries:
        name = label(s) + ("" if s["profile"] == DEFAULT_PROFILE else f" on {s['profile']}")
        for row in s["checks"]:
            worst_cell = f"{format_value(row['worst'])} ({row['worst_seed']})" + ("" if row["passed"] else " **FAIL**")
            lines.append(
                f"| {name} | {row['check']} | {side(row)} {format_value(row['limit'])} | "
                f"{format_value(row['median'])} | {worst_cell} | {row['passed_seeds']}/{len(s['seeds'])} |"
            )
    return "\n".join(lines) + "\n"


def sweep(args: argparse.Namespace, home: Path) -> int:
    todo = cases(args.scenarios, args.profile, CONDITIONS[args.wind])
    print(f"{len(todo)} cases × {len(args.seeds)} seeds, {args.jobs} flights at a time, STACK_HOME {home}", flush=True)
    start = time.monotonic()
    reports: list[list[dict[str, Any]]] = [[] for _ in todo]
    if args.in_process:
        pool: Executor = ProcessPoolExecutor(max_workers=args.jobs, mp_context=multiprocessing.get_context("spawn"))
    else:
        pool = ThreadPoolExecutor(max_workers=args.jobs)
    with pool:
        futures = {
            (
                pool.submit(fly_in_one_process, case.scenario.name, case.profile, seed, case.wind, args.wind_speed)
                if args.in_process
                else pool.submit(
                    fly, case.scenario.name, case.profile, seed, case.wind, home, args.wind_speed, args.vehicles
                )
            ): i
            for i, case in enumerate(todo)
            for seed in args.seeds
        }
        for future in as_completed(futures):
            case, r = todo[futures[future]], future.result()
            reports[futures[future]].append(r)
            detail = r.get("error") or f"{r['wall_time_s']:.0f} s, real-time factor {r['realtime_factor']:.1f}"
            print(f"{case.name} seed {r['seed']}: {'passed' if r['passed'] else 'FAILED'} ({detail})", flush=True)
    summaries = []
    for case, flown in zip(todo, reports, strict=True):
        flown = sorted(flown, key=lambda r: r["seed"])
        summary = summarise(case, flown)
        summaries.append(summary)
        failed = sum(not r["passed"] for r in flown)
        verdict = "holds on every seed" if summary["passed"] else f"FAILS on {failed} of {len(flown)} seeds"
        print(f"\n{case.name} on {case.profile}: {verdict}")
        if args.per_seed:
            print_seeds(case, flown)
            print()
        print_summary(summary)
    failing = [label(s) for s in summaries if not s["passed"]]
    elapsed = time.monotonic() - start
    verdict = f"worst seed misses a limit in: {', '.join(failing)}" if failing else "every limit holds on every seed"
    print(f"\n{len(todo) * len(args.seeds)} flights in {elapsed:.0f} s; {verdict}")
    if args.summary is not None:
        text = json.dumps(summaries, indent=2) if args.summary.suffix == ".json" else markdown(summaries, args.seeds)
        args.summary.write_text(text)
        print(f"summary: {args.summary}")
    return 1 if failing else 0


def main() -> None:
    known = scenarios()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--scenarios",
        type=lambda text: text.split(","),
        default=sorted(known),
        help=f"comma-separated scenarios (default: all of {', '.join(sorted(known))})",
    )
    parser.add_argument("--seeds", type=parse_seeds, default=parse_seeds("1-20"), help="e.g. 1-20 or 1,4,10-12")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="flights at once (default: one per CPU)")
    parser.add_argument(
        "--profile",
        help=f"launch profile (a name in launch/ or a path; default: each scenario's own, or {DEFAULT_PROFILE})",
    )
    parser.add_argument(
        "--wind", choices=sorted(CONDITIONS), default="both", help="calm, in wind (limits doubled), or both"
    )
    parser.add_argument(
        "--wind-speed", type=float, help="the wind's speed in m/s (default: --wind's 5 m/s with gusts, from the west)"
    )
    parser.add_argument(
        "--vehicles", type=int, default=DEFAULT_VEHICLES, help="how many vehicles fly a swarm scenario (default 3)"
    )
    parser.add_argument("--per-seed", action="store_true", help="also print every check's value on every seed")
    parser.add_argument("--summary", type=Path, help="write the summary to this file: JSON if .json, else markdown")
    parser.add_argument("--home", type=Path, help="STACK_HOME to keep the runs, reports and outputs in")
    parser.add_argument(
        "--in-process", action="store_true", help="fly each flight in one process (the same flight, less CPU)"
    )
    args = parser.parse_args()
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    unknown = [s for s in args.scenarios if s not in known]
    if unknown:
        parser.error(f"unknown scenario {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    processes_only = [s for s in args.scenarios if s in PROCESSES_ONLY]
    if args.in_process and processes_only:
        parser.error(f"--in-process cannot fly {', '.join(processes_only)}: {PROCESSES_ONLY[processes_only[0]]}")
    if args.home is not None:
        args.home.mkdir(parents=True, exist_ok=True)
        raise SystemExit(sweep(args, args.home.resolve()))
    with tempfile.TemporaryDirectory(prefix="sweep-") as tmp:
        code = sweep(args, Path(tmp))
    raise SystemExit(code)


if __name__ == "__main__":
    main()
