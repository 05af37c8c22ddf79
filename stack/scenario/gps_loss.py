"""Scenario ``gps_loss``: GPS fails for 10 s while the vehicle holds at 5 m, then comes back.

The failure is injected the way PX4's ``failure gps off`` does it (MAV_CMD_INJECT_FAILURE, acted on by
the simulator), at an exact simulated time. The estimator dead-reckons on the IMU; if its uncertainty
grows past what the commander trusts, the commander's failsafe lands the vehicle. Either way it must
stay within 5 m of where it held, and end landed or holding again on a valid estimate. After the
outage and 15 s more, the script lands whatever is still flying.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.commander.modes import mode_name
from stack.msg.registry import ORB_ID
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.script import ScriptContext, Wait

ALTITUDE_M = 5.0
HOLD_BEFORE_S = 5.0
OUTAGE_S = 10.0
AFTER_S = 15.0
CMD = autonomy.CMD


def inject_gps(ctx: ScriptContext, failure_type: int) -> Generator[Wait, None, None]:
    yield from ctx.command(
        CMD.VEHICLE_CMD_INJECT_FAILURE, param1=float(CMD.FAILURE_UNIT_SENSOR_GPS), param2=float(failure_type)
    )


def gps_outage(ctx: ScriptContext, outage_s: float, after_s: float) -> Generator[Wait, None, None]:
    """GPS off for ``outage_s``, then on and ``after_s`` more; the times in ``gps_off_at`` and ``gps_on_at``."""
    yield from inject_gps(ctx, CMD.FAILURE_TYPE_OFF)
    ctx.state["gps_off_at"] = ctx.now
    yield ctx.wait(outage_s)
    yield from inject_gps(ctx, CMD.FAILURE_TYPE_OK)
    ctx.state["gps_on_at"] = ctx.now
    yield ctx.wait(after_s)


def watch_modes(ctx: ScriptContext) -> None:
    """Note the first failsafe mode the commander picks during and after the outage, and when."""
    status = ctx.latest.get(ORB_ID.vehicle_status)
    if "gps_off_at" in ctx.state and "failsafe_mode" not in ctx.state and status is not None and status.failsafe:
        ctx.state["failsafe_mode"] = mode_name(status.nav_state)
        ctx.state["failsafe_at"] = ctx.now
        ctx.log(f"failsafe: {ctx.state['failsafe_mode']}")


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    ctx.tick_hooks.append(lambda: watch_modes(ctx))
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    home = ctx.latest[ORB_ID.home_position]
    yield ctx.until(lambda: autonomy.settled(ctx, home.z - ALTITUDE_M), 30.0, "the climb to settle")
    yield ctx.wait(HOLD_BEFORE_S)
    yield from gps_outage(ctx, OUTAGE_S, AFTER_S)
    lpos = ctx.latest[ORB_ID.vehicle_local_position]
    ctx.state["recovered"] = (
        autonomy.armed(ctx) and lpos.xy_valid and autonomy.nav_state(ctx) == (autonomy.NS.NAVIGATION_STATE_AUTO_LOITER)
    )
    if autonomy.armed(ctx):
        if autonomy.nav_state(ctx) != autonomy.NS.NAVIGATION_STATE_AUTO_LAND:
            yield from ctx.command(CMD.VEHICLE_CMD_NAV_LAND)
        yield from autonomy.wait_disarmed(ctx, 90.0)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    t_off = ctx.state["gps_off_at"]
    t_end = ctx.state["gps_on_at"] + AFTER_S
    hold = frames.truth_about_home(autonomy.truth_at(frames.truth, t_off).position)
    deviation = 0.0
    for t, truth in zip(frames.truth.times, frames.truth.values, strict=True):
        if t_off <= t <= t_end:
            p = frames.truth_about_home(truth.position)
            deviation = max(deviation, math.hypot(p[0] - hold[0], p[1] - hold[1]))
    landed = autonomy.landed_and_disarmed(ctx)
    recovered = bool(ctx.state.get("recovered", False))
    flight = (ctx.state["armed_at"], ctx.state.get("disarmed_at", ctx.now))
    return {
        "max_pos_deviation_m": deviation,
        "failsafe_action": ctx.state.get("failsafe_mode", "none"),
        "recovered": recovered,
        "landed_and_disarmed": landed,
        "landed_or_recovered": landed or recovered,
        "est_pos_error_rms_m": autonomy.estimate_error_rms(ctx, frames, *flight),
    }


SCENARIO = Scenario(
    name="gps_loss",
    description="GPS off for 10 s during a hold at 5 m: dead reckoning or failsafe, then recover or land",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("max_pos_deviation_m", 5.0),
        Check("landed_or_recovered", True),
    ),
    record=autonomy.RECORD,
    watch=autonomy.WATCH,
    timeout_s=240.0,
)
