"""Scenario ``plane_mission``: a fixed-wing mission from runway to runway.

The mission is the profile's choice (option ``mission``), sized for the aircraft: by default
``launch/missions/plane_rectangle.plan`` for the SIH airplane, a runway takeoff to 30 m, a rectangle of four
straight legs of 300–400 m at 40 m and a loiter of two circles; ``c172_rectangle`` for a Cessna 172, whose turns
at cruise are 150–300 m across, the same at 120 m over legs of 1.5–1.8 km. Then Return: home at RTL_RETURN_ALT,
a descending loiter, the approach on the runway's centre line and the landing.
Judged on the ground truth about home (:mod:`stack.scenario.plane_metrics`): the cross-track error on the second
half of each leg (RMS and max), the altitude and true-airspeed errors there, the turns' overshoot past the next
leg, the loiter's radius error, and where the aircraft came to rest.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.fw.runway import on_runway
from stack.launch_files import find_mission
from stack.mathlib import quaternion as quat
from stack.mission.items import LOITER_COMMANDS, MAV_CMD_NAV_WAYPOINT, GeoPoint, Mission
from stack.mission.loader import load_mission
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleStatus
from stack.scenario import autonomy, plane_metrics
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.metrics import value_at
from stack.scenario.mission_box import upload
from stack.scenario.script import ScenarioError, ScriptContext, Wait

MISSION = "plane_rectangle"
MISSION_TIMEOUT_S = 900.0
TOUCHDOWN_SINK_MAX = 2.0
"""[m/s]: a firm landing; a stalled flare hits the runway at 3 m/s or more."""
RECORD = (*autonomy.RECORD, ORB_ID.mission_result, ORB_ID.tecs_status, ORB_ID.position_setpoint_triplet)


def require_fixed_wing(ctx: ScriptContext) -> Generator[Wait, None, None]:
    """Refuse, in one line, to fly a plane's scenario on another vehicle."""
    yield ctx.until(lambda: ORB_ID.vehicle_status in ctx.latest, autonomy.READY_TIMEOUT_S, "the vehicle's status")
    if ctx.latest[ORB_ID.vehicle_status].vehicle_type != VehicleStatus.VEHICLE_TYPE_FIXED_WING:
        raise ScenarioError("this scenario flies a fixed-wing profile (sitl_plane, sitl_plane_npfg, jsbsim_c172)")


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from require_fixed_wing(ctx)
    yield from autonomy.wait_ready(ctx)
    home_msg = ctx.latest[ORB_ID.home_position]
    home = GeoPoint(home_msg.lat, home_msg.lon, home_msg.alt)
    try:
        path = find_mission(ctx.options["mission"])
    except FileNotFoundError as e:
        raise ScenarioError(f"option mission: {e}") from None
    mission = load_mission(path, home)
    ctx.state["mission"] = mission
    yield from upload(ctx, mission, home)
    yield from ctx.command(autonomy.CMD.VEHICLE_CMD_MISSION_START, param1=0.0)
    ctx.state["armed_at"] = ctx.now
    yield from autonomy.wait_disarmed(ctx, MISSION_TIMEOUT_S)
    yield ctx.wait(1.0)


def flight_samples(ctx: ScriptContext, frames: autonomy.Frames, t0: float, t1: float) -> list[plane_metrics.Sample]:
    """The truth about home with its true airspeed and TECS' airspeed setpoint, over [t0, t1]."""
    tecs = ctx.series.get(ORB_ID.tecs_status)
    out = []
    for t, truth in zip(frames.truth.times, frames.truth.values, strict=True):
        if not t0 <= t <= t1:
            continue
        v, w = truth.velocity, truth.wind
        airspeed = math.dist(v, w)
        sp = value_at(tecs.times, tecs.values, t).true_airspeed_sp if tecs is not None and tecs.times else math.nan
        out.append(plane_metrics.Sample(t, frames.truth_about_home(truth.position), airspeed, sp))
    return out


def by_item(ctx: ScriptContext, samples: list[plane_metrics.Sample]) -> dict[int, list[plane_metrics.Sample]]:
    """The samples flown while each mission item was the current one."""
    results = ctx.series.get(ORB_ID.mission_result)
    if results is None:
        raise ScenarioError("no mission_result was received")
    seqs = [m.seq_current for m in results.values]
    out: dict[int, list[plane_metrics.Sample]] = {}
    for s in samples:
        out.setdefault(value_at(results.times, seqs, s.t), []).append(s)
    return out


def loiter_radius(ctx: ScriptContext, t0: float, t1: float) -> float:
    """The radius the navigator gave the loiter setpoints between t0 and t1 (NaN: none)."""
    triplets = ctx.series.get(ORB_ID.position_setpoint_triplet)
    if triplets is None:
        return math.nan
    radii = [m.current.loiter_radius for t, m in zip(triplets.times, triplets.values, strict=True) if t0 <= t <= t1]
    return next((r for r in reversed(radii) if math.isfinite(r)), math.nan)


def landing(ctx: ScriptContext, frames: autonomy.Frames) -> dict[str, Any]:
    t0 = ctx.state["armed_at"]
    heading = quat.yaw(autonomy.truth_at(frames.truth, t0).q)
    rest = frames.truth_about_home(frames.truth.values[-1].position)
    ok, along, across = on_runway((rest[0], rest[1]), (0.0, 0.0), heading)
    flown = [s for t, s in zip(frames.truth.times, frames.truth.values, strict=True) if t >= t0]
    sink = plane_metrics.touchdown_sink([s.on_ground for s in flown], [s.velocity[2] for s in flown])
    return {
        "touchdown_sink_m_s": sink,
        "landed_on_runway": ok and autonomy.landed_and_disarmed(ctx),
        "landing_along_m": along,
        "landing_offset_m": across,
        "landed_and_disarmed": autonomy.landed_and_disarmed(ctx),
    }


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    mission: Mission = ctx.state["mission"]
    t0, t1 = ctx.state["armed_at"], ctx.state.get("disarmed_at", ctx.now)
    samples = flight_samples(ctx, frames, t0, t1)
    flown = by_item(ctx, samples)
    corners = [item for item in mission if item.command == MAV_CMD_NAV_WAYPOINT]
    xtrack: list[float] = []
    altitude: list[float] = []
    airspeed: list[float] = []
    overshoot = 0.0
    for i in range(len(corners) - 1):
        a, b = corners[i], corners[i + 1]
        errors = plane_metrics.leg_errors(flown.get(b.index, []), (a.north, a.east), (b.north, b.east), -b.down)
        xtrack += errors.xtrack
        altitude += errors.altitude
        airspeed += errors.airspeed
        if i > 0:
            before = corners[i - 1]
            overshoot = max(
                overshoot,
                plane_metrics.turn_overshoot(
                    flown.get(b.index, []), (before.north, before.east), (a.north, a.east), (b.north, b.east)
                ),
            )
    loiter = next((item for item in mission if item.command in LOITER_COMMANDS), None)
    loiter_errors: list[float] = []
    if loiter is not None:
        circling = flown.get(loiter.index, [])
        radius = abs(loiter.loiter_radius) if math.isfinite(loiter.loiter_radius) else math.nan
        if circling and not math.isfinite(radius):
            radius = loiter_radius(ctx, circling[0].t, circling[-1].t)
        loiter_errors = plane_metrics.loiter_radius_errors(circling, (loiter.north, loiter.east), radius)
    xtrack_rms, xtrack_max = plane_metrics.summary(xtrack)
    return {
        "xtrack_rms_m": xtrack_rms,
        "xtrack_max_m": xtrack_max,
        "turn_overshoot_max_m": overshoot,
        "loiter_radius_rms_m": plane_metrics.summary(loiter_errors)[0],
        "altitude_rms_m": plane_metrics.summary(altitude)[0],
        "airspeed_rms_m_s": plane_metrics.summary(airspeed)[0],
        **landing(ctx, frames),
        "mission_time_s": t1 - t0,
        "est_pos_error_rms_m": autonomy.estimate_error_rms(ctx, frames, t0, t1),
    }


CHECKS = (
    Check("xtrack_rms_m", 1.0),
    Check("xtrack_max_m", 3.0),
    Check("loiter_radius_rms_m", 2.0),
    Check("altitude_rms_m", 1.5),
    Check("airspeed_rms_m_s", 1.0),
    Check("landed_on_runway", True),
    Check("touchdown_sink_m_s", TOUCHDOWN_SINK_MAX),
)

SCENARIO = Scenario(
    name="plane_mission",
    description="Fixed-wing: runway takeoff, a rectangle sized for the aircraft, two loiter circles, return, landing",
    script=script,
    evaluate=evaluate,
    checks=CHECKS,
    record=RECORD,
    watch=(ORB_ID.vehicle_land_detected,),
    publish=(ORB_ID.mission,),
    timeout_s=MISSION_TIMEOUT_S + 120.0,
    profile="sitl_plane",
    options={"mission": MISSION},
)
