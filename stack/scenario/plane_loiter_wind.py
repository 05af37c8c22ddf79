"""Scenario ``plane_loiter_wind``: a fixed-wing loiter in an 8 m/s wind (with gusts), then return and landing.

Runway takeoff (into the wind) to 40 m, then Hold: the navigator circles the point where Hold began at
NAV_LOITER_RAD at the takeoff altitude. Once the aircraft is on the circle, three full circles are judged on the
ground truth: the radius error (RMS), the altitude error and the true-airspeed error against TECS' setpoint. In
wind a guidance that ignores the wind (L1) flies an egg-shaped circle; NPFG, fed the airspeed selector's wind
estimate, should hold it better.
Then Return and a landing on the runway. The limits are the calm limits doubled (`stack fly --wind`'s rule). The
touchdown's sink rate is reported, not judged here (plane_mission judges the touchdown).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.msg.fixedwing import PositionSetpoint
from stack.msg.registry import ORB_ID
from stack.scenario import autonomy, plane_metrics
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.plane_mission import RECORD, flight_samples, landing, require_fixed_wing
from stack.scenario.script import ScenarioError, ScriptContext, Wait

ALTITUDE_M = 40.0
CIRCLES = 3
WIND_SPEED_M_S = 8.0
CAPTURE_TIMEOUT_S = 120.0


def _loiter_setpoint(ctx: ScriptContext) -> PositionSetpoint | None:
    triplet = ctx.latest.get(ORB_ID.position_setpoint_triplet)
    if triplet is None or triplet.current.type != PositionSetpoint.SETPOINT_TYPE_LOITER:
        return None
    return triplet.current


def on_circle(ctx: ScriptContext) -> bool:
    """The estimate puts the vehicle on the Hold circle it was given (within a fifth of its radius)."""
    sp = _loiter_setpoint(ctx)
    lpos = ctx.latest.get(ORB_ID.vehicle_local_position)
    if sp is None or lpos is None:
        return False
    distance = math.hypot(lpos.x - sp.x, lpos.y - sp.y)
    return abs(distance - sp.loiter_radius) <= plane_metrics.ON_CIRCLE_FRACTION * sp.loiter_radius


def circling_time(ctx: ScriptContext, radius: float, circles: float) -> float:
    """How long ``circles`` circles of ``radius`` take at the current ground speed [s]."""
    lpos = ctx.latest[ORB_ID.vehicle_local_position]
    return circles * 2.0 * math.pi * radius / max(math.hypot(lpos.vx, lpos.vy), 1.0)


def record_loiter(ctx: ScriptContext) -> PositionSetpoint:
    """Keep the circle being flown, about home (north, east, altitude, radius), in ``ctx.state["loiter"]``."""
    sp = _loiter_setpoint(ctx)
    if sp is None:
        raise ScenarioError("no loiter setpoint")
    home = ctx.latest[ORB_ID.home_position]
    ctx.state["loiter"] = (sp.x - home.x, sp.y - home.y, home.z - sp.z, sp.loiter_radius)
    return sp


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from require_fixed_wing(ctx)
    yield from autonomy.wait_ready(ctx)
    yield from autonomy.take_off(ctx, ALTITUDE_M)
    yield ctx.until(lambda: on_circle(ctx), CAPTURE_TIMEOUT_S, "the loiter circle")
    sp = record_loiter(ctx)
    duration = circling_time(ctx, sp.loiter_radius, CIRCLES)
    ctx.state["judged"] = (ctx.now, ctx.now + duration)
    ctx.log(f"on the {sp.loiter_radius:g} m circle: judging {CIRCLES} circles ({duration:.0f} s)")
    yield ctx.wait(duration)
    yield from ctx.command(autonomy.CMD.VEHICLE_CMD_NAV_RETURN_TO_LAUNCH)
    yield from autonomy.wait_disarmed(ctx, 600.0)
    yield ctx.wait(1.0)


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    if "judged" not in ctx.state:
        raise ScenarioError("the loiter was never reached")
    t0, t1 = ctx.state["judged"]
    north, east, altitude_sp, radius = ctx.state["loiter"]
    samples = flight_samples(ctx, frames, t0, t1)
    errors = plane_metrics.loiter_radius_errors(samples, (north, east), radius)
    altitude = [-s.position[2] - altitude_sp for s in samples]
    airspeed = [s.airspeed - s.airspeed_sp for s in samples if math.isfinite(s.airspeed_sp)]
    rms, worst = plane_metrics.summary(errors)
    return {
        "loiter_radius_rms_m": rms,
        "loiter_radius_max_m": worst,
        "altitude_rms_m": plane_metrics.summary(altitude)[0],
        "airspeed_rms_m_s": plane_metrics.summary(airspeed)[0],
        **landing(ctx, frames),
        "flight_time_s": ctx.state.get("disarmed_at", ctx.now) - ctx.state["armed_at"],
    }


SCENARIO = Scenario(
    name="plane_loiter_wind",
    description=f"Fixed-wing: {CIRCLES} loiter circles at {ALTITUDE_M:g} m in {WIND_SPEED_M_S:g} m/s wind, then return",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("loiter_radius_rms_m", 4.0),
        Check("altitude_rms_m", 3.0),
        Check("airspeed_rms_m_s", 2.0),
        Check("landed_on_runway", True),
    ),
    record=RECORD,
    watch=(ORB_ID.vehicle_land_detected, ORB_ID.position_setpoint_triplet),
    params={"SIM_WIND_SPD": WIND_SPEED_M_S, "SIM_WIND_DIR": 0.0, "SIM_WIND_GUST": 1.0},
    timeout_s=1200.0,
    profile="sitl_plane",
)
