"""Scenario ``takeoff_land``: take off to 5 m, hold for 20 s, land and disarm, all in auto modes.

The hold starts once the trajectory has arrived at the takeoff altitude and the vehicle had 3 s to
settle; the hover metrics are over those 20 s, from the ground truth against the setpoint (both
about home, see :mod:`stack.scenario.autonomy`); the estimate error is over the whole flight.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.msg.registry import ORB_ID
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.metrics import rms
from stack.scenario.script import ScriptContext, Wait

ALTITUDE_M = 5.0
HOLD_S = 20.0
SETTLE_S = 3.0


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield ctx.until(lambda: autonomy.settled(ctx, home.z - ALTITUDE_M), 30.0, "the climb to settle")
    yield ctx.wait(SETTLE_S)
    ctx.state["hold"] = (ctx.now, ctx.now + HOLD_S)
    ctx.log(f"holding for {HOLD_S:g} s")
    yield ctx.wait(HOLD_S)
    yield from autonomy.land(ctx)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    t0, t1 = ctx.state["hold"]
    alt_errors, pos_errors = [], []
    for t, sp in autonomy.setpoints_between(ctx, t0, t1):
        truth = frames.truth_about_home(autonomy.truth_at(frames.truth, t).position)
        target = frames.local_about_home(sp.position)
        alt_errors.append(abs(truth[2] - target[2]))
        pos_errors.append(math.hypot(truth[0] - target[0], truth[1] - target[1]))
    flight = (ctx.state["armed_at"], ctx.state.get("disarmed_at", ctx.now))
    return {
        "hover_alt_error_max_m": max(alt_errors, default=math.nan),
        "hover_pos_error_rms_m": rms(pos_errors),
        "hover_pos_error_max_m": max(pos_errors, default=math.nan),
        "landed_and_disarmed": autonomy.landed_and_disarmed(ctx),
        "est_pos_error_rms_m": autonomy.estimate_error_rms(ctx, frames, *flight),
        "max_tilt_deg": autonomy.max_tilt_deg(frames, *flight),
        "flight_time_s": flight[1] - flight[0],
    }


SCENARIO = Scenario(
    name="takeoff_land",
    description="Take off to 5 m, hold 20 s, land and disarm (auto modes)",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("hover_alt_error_max_m", 0.15),
        Check("hover_pos_error_rms_m", 0.10),
        Check("landed_and_disarmed", True),
        Check("est_pos_error_rms_m", 0.3),
    ),
    record=autonomy.RECORD,
    watch=autonomy.WATCH,
    timeout_s=180.0,
)
