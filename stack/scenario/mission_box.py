"""Scenario ``mission_box``: upload ``launch/missions/box.plan`` (a 20 m square at 10 m, then return) and fly it.

The mission goes up the way ``stack cmd mission`` sends it (the QGroundControl plan converted about
the vehicle's home, published on ``mission``, answered on ``mission_result``); MISSION_START arms
the vehicle and the mission's return item brings it home to land. Judged from the ground truth
about home: the closest approach to each corner, the distance from each straight leg while flying
it, where it touched down, and how long the mission took.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

from stack.launch_files import find_launch_file
from stack.mission.items import MAV_CMD_NAV_WAYPOINT, GeoPoint, Mission
from stack.mission.loader import load_mission
from stack.mission.transfer import mission_id_for, mission_message
from stack.msg.registry import ORB_ID
from stack.scenario import autonomy
from stack.scenario.catalogue import Check, Scenario
from stack.scenario.metrics import value_at
from stack.scenario.script import ScenarioError, ScriptContext, Wait

MISSION_FILE = "missions/box.plan"
Vec2 = tuple[float, float]


def upload(ctx: ScriptContext, mission: Mission, home: GeoPoint | None) -> Generator[Wait, None, None]:
    """Publish the mission and wait for the navigator to accept it."""
    mission_id = mission_id_for(mission)
    ctx.publish(ORB_ID.mission, mission_message(mission, home, mission_id))

    def answered() -> bool:
        result = ctx.latest.get(ORB_ID.mission_result)
        return result is not None and result.mission_id == mission_id

    yield ctx.until(answered, 5.0, "the navigator's answer to the mission upload")
    result = ctx.latest[ORB_ID.mission_result]
    if not result.valid:
        raise ScenarioError(f"mission refused: {result.reason}")
    ctx.log(f"mission accepted: {result.seq_total} items")


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from autonomy.wait_ready(ctx)
    home_msg = ctx.latest[ORB_ID.home_position]
    home = GeoPoint(home_msg.lat, home_msg.lon, home_msg.alt)
    mission = load_mission(find_launch_file(MISSION_FILE), home)
    ctx.state["mission"] = mission
    yield from upload(ctx, mission, home)
    yield from ctx.command(autonomy.CMD.VEHICLE_CMD_MISSION_START, param1=0.0)
    ctx.state["armed_at"] = ctx.now
    yield from autonomy.wait_disarmed(ctx, 240.0)
    yield ctx.wait(1.0)


def _segment_distance(p: tuple[float, float, float], a: tuple[float, ...], b: tuple[float, ...]) -> float:
    ab = [b[i] - a[i] for i in range(3)]
    ap = [p[i] - a[i] for i in range(3)]
    length_sq = sum(v * v for v in ab)
    u = 0.0 if length_sq == 0.0 else max(0.0, min(1.0, sum(ab[i] * ap[i] for i in range(3)) / length_sq))
    return math.dist(p, [a[i] + u * ab[i] for i in range(3)])


def evaluate(ctx: ScriptContext) -> dict[str, Any]:
    frames = autonomy.Frames(ctx)
    mission: Mission = ctx.state["mission"]
    results = ctx.series.get(ORB_ID.mission_result)
    if results is None:
        raise ScenarioError("no mission_result was received")
    t0, t1 = ctx.state["armed_at"], ctx.state.get("disarmed_at", ctx.now)
    takeoff = next(item for item in mission if item.has_position)
    corners = [item for item in mission if item.command == MAV_CMD_NAV_WAYPOINT]
    # The mission was planned about home before arming, which set home again: each corner is its place.
    places = [(*frames.place_about_home(c.lat, c.lon, c.north, c.east), c.down) for c in corners]
    # The first leg starts above home at the takeoff altitude.
    points = [(0.0, 0.0, takeoff.down), *places]
    closest = [math.inf] * len(corners)
    track = 0.0
    seq_times, seqs = results.times, [m.seq_current for m in results.values]
    for t, truth in zip(frames.truth.times, frames.truth.values, strict=True):
        if not t0 <= t <= t1:
            continue
        p = frames.truth_about_home(truth.position)
        for i, place in enumerate(places):
            closest[i] = min(closest[i], math.dist(p, place))
        seq = value_at(seq_times, seqs, t)
        leg = next((i for i, c in enumerate(corners) if c.index == seq), None)
        if leg is not None:
            track = max(track, _segment_distance(p, points[leg], points[leg + 1]))
    touchdown = frames.truth_about_home(autonomy.truth_at(frames.truth, t1).position)
    return {
        "waypoint_error_max_m": max(closest),
        "track_error_max_m": track,
        "land_error_m": math.hypot(touchdown[0], touchdown[1]),
        "landed_and_disarmed": autonomy.landed_and_disarmed(ctx),
        "mission_time_s": t1 - t0,
        "est_pos_error_rms_m": autonomy.estimate_error_rms(ctx, frames, t0, t1),
        "max_tilt_deg": autonomy.max_tilt_deg(frames, t0, t1),
    }


SCENARIO = Scenario(
    name="mission_box",
    description="Fly launch/missions/box.plan: a 20 m square at 10 m, then return and land",
    script=script,
    evaluate=evaluate,
    checks=(
        Check("waypoint_error_max_m", 0.3),
        Check("track_error_max_m", 1.0),
        Check("land_error_m", 0.5),
        Check("landed_and_disarmed", True),
    ),
    record=(*autonomy.RECORD, ORB_ID.mission_result),
    watch=(ORB_ID.vehicle_land_detected,),
    publish=(ORB_ID.mission,),
    timeout_s=300.0,
)
