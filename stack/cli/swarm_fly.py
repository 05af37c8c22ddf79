"""``stack fly SCENARIO --vehicles N``: a swarm scenario flown by N vehicles in one world, judged as one flight.

Each vehicle is a `stack fly` of its own on the world clock (stack.cli.swarm_launch), its scenario module in the
vehicle's part (leader or follower, stack.scenario.swarm_flight), writing its result where this process reads
it. The swarm's checks are made here from every vehicle's result (Swarm.evaluate), with the profile's limits for
the scenario (doubled in wind, as for one vehicle); the report gives them, each vehicle's figures and where its
logs are.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import typer

from stack.cli.common import fail
from stack.cli.fly import print_summary
from stack.cli.swarm_hub import Hub
from stack.cli.swarm_launch import check_swarm, run_swarm
from stack.scenario.catalogue import Scenario
from stack.scenario.flight import WIND_SPEED, windy_limits
from stack.supervisor import state as run_state
from stack.supervisor.profile import Profile


def fly_swarm(
    prof: Profile,
    scenario: Scenario,
    count: int,
    args: Sequence[str],
    report: Path | None,
    spread: Spread | None = None,
) -> int:
    """Fly ``scenario`` with ``count`` vehicles of ``prof`` (each ``stack ARGS``), or with ``spread`` this machine's
    share of them; 0 if the swarm's checks pass."""
    assert scenario.swarm is not None
    try:
        names = check_swarm(prof, count)
    except ValueError as e:
        fail(str(e), code=2)
    here = names if spread is None else spread.here
    unknown = [n for n in here if n not in names]
    if unknown:
        fail(f"--here: no vehicle {', '.join(unknown)} in a swarm of {', '.join(names)}", code=2)
    running = [n for n in here if run_state.addressed_stacks(n)]
    if running:
        fail(f"a stack for vehicle '{running[0]}' is already running; `stack down` first")
    run_dir = run_state.new_run_dir(scenario.name, "swarm")
    paths = {name: run_dir / f"{name}.result.json" for name in here}
    typer.echo(f"[swarm] {scenario.name} with {', '.join(names)} (seed {prof.seed}); logs in {run_dir}")
    started = time.monotonic()

    def own(name: str) -> list[str]:
        return ["--swarm-result", str(paths[name])]

    if spread is None:
        run_swarm(names, args, run_dir, own)
        heard: dict[str, dict[str, Any]] = {}
    else:
        hub = Hub(spread.listen, spread.join, spread.tls, spread.access, spread.count_denials)
        try:
            run_swarm(names, args, run_dir, own, here=here, hub=hub.local)
            hub.wait_results([n for n in names if n not in here])
            heard = dict(hub.results)
        finally:
            hub.close()
    wall = time.monotonic() - started
    results: list[dict[str, Any] | None] = [
        json.loads(paths[n].read_text()) if n in paths and paths[n].exists() else heard.get(n) for n in names
    ]
    error = next((f"{n}: {r['error']}" for n, r in zip(names, results, strict=True) if r and r["error"]), None)
    metrics: dict[str, Any] = {}
    if error is None:
        try:
            metrics = scenario.swarm.evaluate(results, prof.swarm_spacing_m)
        except ValueError as e:
            error = str(e)
    wind = "--wind" in args or "--wind-speed" in args
    limits = dict(prof.scenario_limits.get(scenario.name, {}))
    if wind:
        limits = windy_limits(scenario.swarm.checks, limits)
    checks = []
    for check in scenario.swarm.checks:
        limit = limits.get(check.metric, check.limit)
        value = metrics.get(check.metric)
        ok = error is None and type(check)(check.metric, limit, check.at_least).passed(value)
        checks.append({"name": check.metric, "value": value, "limit": limit, "passed": ok})
    sim = max((r["sim_time_s"] for r in results if r is not None), default=0.0)
    full = {
        "scenario": scenario.name,
        "profile": prof.name,
        "seed": prof.seed,
        "vehicles": names,
        "wind": wind,
        "wind_speed_m_s": _wind_speed(args) if wind else 0.0,
        "passed": error is None and all(c["passed"] for c in checks),
        "sim_time_s": sim,
        "wall_time_s": wall,
        "realtime_factor": sim / wall if wall > 0 else 0.0,
        "metrics": metrics,
        "checks": checks,
        "error": error,
        "run_dir": str(run_dir),
        "recording": None,
        "by_vehicle": {
            n: None if r is None else {"metrics": r["metrics"], "error": r["error"]}
            for n, r in zip(names, results, strict=True)
        },
    }
    out = report or run_dir / "report.json"
    out.write_text(json.dumps(full, indent=2))
    print_summary(full, out)
    return 0 if full["passed"] else 1


@dataclass(frozen=True)
class Spread:
    """This machine's share of a swarm spread over several: its vehicles, where its hub listens for the other
    machines' and where it reaches theirs, and over ``tls/`` what it presents and lets in (stack.cli.swarm_hub)."""

    here: list[str]
    listen: list[str]
    join: list[str]
    tls: dict[str, str] = field(default_factory=dict)
    access: dict[str, object] = field(default_factory=dict)
    count_denials: bool = True


def _wind_speed(args: Sequence[str]) -> float:
    return float(args[list(args).index("--wind-speed") + 1]) if "--wind-speed" in args else WIND_SPEED
