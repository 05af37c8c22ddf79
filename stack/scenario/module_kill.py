"""Scenario ``module_kill``: each control module the profile runs is killed in turn (SIGKILL, as a crash ends it)
during a hover.

The control modules restart by default. Modules sharing the simulator's process (``process = "NAME"``) are left
alone: killing one would end the simulated world with it; a module sharing a process with others takes them
down too, and they come back together. In lockstep, simulated time waits while the supervisor restarts a dead
module, so the flight must simply go on: after each restart the vehicle is still armed, in its mode, holding where
it was. In real time the vehicle flies on without the module until the commander notices it (within 100 ms) and
takes its failsafe (:mod:`stack.commander.control_chain`): flight termination for a loss of attitude control,
landing for a loss of position control; the scenario then reports what happened and ends, and the checks, which
are those of the lockstep flight, fail.

Each estimator keeps its state every 0.2 s of its clock and a restarted one resumes from it (the position
estimator in the same frame, so home and the setpoints keep their meaning); the worst deviation from the hold,
about 0.15 m, is the hover's own.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.commander.control_chain import CHAIN
from stack.commander.modes import mode_name
from stack.msg.registry import ORB_ID
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.script import ScriptContext, Wait

ALTITUDE_M = 5.0
HOLD_AFTER_S = 4.0
RESTART_TIMEOUT_S = 30.0
MODULES: tuple[str, ...] = (*(link.module for link in CHAIN), "commander")


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield ctx.until(lambda: autonomy.settled(ctx, home.z - ALTITUDE_M), 30.0, "the climb to settle")
    yield ctx.wait(2.0)
    kills: list[dict[str, Any]] = []
    ctx.state["kills"] = kills
    # The chain's modules this profile runs (the RotorS profiles run RotorS' controller instead of three of PX4's),
    # but those sharing the simulator's process: killing one would end the simulated world with it.
    world = ctx.pid("simulator")
    running = [m for m in MODULES if ctx.pid(m) is not None]
    beside_world = [m for m in running if ctx.pid(m) == world]
    if beside_world:
        ctx.log(f"not killing {', '.join(beside_world)}: they share the simulator's process")
    ctx.state["modules"] = running = [m for m in running if m not in beside_world]
    for module in running:
        if not autonomy.armed(ctx):
            break
        mode_before = autonomy.nav_state(ctx)
        killed_at = ctx.now
        old_pid = ctx.kill(module)
        yield ctx.until(lambda m=module, p=old_pid: ctx.pid(m) not in (None, p), RESTART_TIMEOUT_S, f"{module} back")
        back_at = ctx.now
        yield ctx.wait(HOLD_AFTER_S)
        status = ctx.latest[ORB_ID.vehicle_status]
        kill = {
            "module": module,
            "killed_at": killed_at,
            "back_after_s": back_at - killed_at,
            "end": ctx.now,
            "armed": autonomy.armed(ctx),
            "mode": mode_name(status.nav_state),
            "resumed": autonomy.armed(ctx) and status.nav_state == mode_before and not status.failsafe,
        }
        kills.append(kill)
        ctx.log(
            f"{module}: back after {kill['back_after_s']:.2f} s, {'armed' if kill['armed'] else 'disarmed'}, "
            f"{kill['mode']}{'' if kill['resumed'] else ' (did not resume)'}"
        )
    if autonomy.armed(ctx):
        yield from autonomy.land(ctx)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    kills: list[dict[str, Any]] = ctx.state.get("kills", [])
    metrics: dict[str, Any] = {}
    worst = 0.0
    for kill in kills:
        hold = frames.truth_about_home(autonomy.truth_at(frames.truth, kill["killed_at"]).position)
        deviation = 0.0
        for t, truth in zip(frames.truth.times, frames.truth.values, strict=True):
            if kill["killed_at"] <= t <= kill["end"]:
                p = frames.truth_about_home(truth.position)
                deviation = max(deviation, math.dist(p, hold))
        metrics[f"{kill['module']}_deviation_m"] = deviation
        worst = max(worst, deviation)
    metrics["modules_killed"] = len(kills)
    running = ctx.state.get("modules", MODULES)
    metrics["all_resumed"] = bool(kills) and len(kills) == len(running) and all(k["resumed"] for k in kills)
    metrics["max_deviation_m"] = worst
    metrics["landed_and_disarmed"] = autonomy.landed_and_disarmed(ctx)
    return metrics


SCENARIO = Scenario(
    name="module_kill",
    description="Each control module killed in turn during a hover at 5 m: restarted, the flight goes on",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("all_resumed", True),
        Check("max_deviation_m", 0.5),
        Check("landed_and_disarmed", True),
    ),
    record=autonomy.RECORD,
    watch=autonomy.WATCH,
    timeout_s=300.0,
)
