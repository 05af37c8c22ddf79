"""Scenario ``swarm_leader_loss``: the swarm of ``swarm_formation`` loses its leader in the middle of the box.

KILLED_AFTER_S into the box, every process of the leader is killed (SIGKILL, supervisor first), as a crash or a
power loss would end it. Each follower must notice within a second (it hears nothing newer than
LEADER_TIMEOUT_S), never follow a position older than that, and take the profile's choice (``[scenario.
swarm_leader_loss] on_leader_loss = "hold"`` or ``"land"``): in Hold it must stay where it stopped; then it lands.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

from stack.scenario import formation, swarm_flight
from stack.scenario.catalogue import Check
from stack.scenario.script import ScriptContext, Wait
from stack.scenario.swarm_track import Tracks, metric

KILLED_AFTER_S = 15.0
MODES = {"hold": "Hold", "land": "Land"}


def script(ctx: ScriptContext) -> Generator[Wait, None, None]:
    yield from swarm_flight.script(ctx, KILLED_AFTER_S)


def evaluate_swarm(results: list[dict[str, Any] | None], spacing_m: float) -> dict[str, Any]:
    killed_at = metric(results, 1, "killed_at")
    if killed_at is None:
        raise ValueError("the leader was not killed")
    followers = range(2, len(results) + 1)
    if any(results[s - 1] is None for s in followers):
        raise ValueError("a follower wrote no result")
    lost = [metric(results, s, "leader_lost_at") for s in followers]
    drifts = [metric(results, s, "hold_drift_m") for s in followers]
    chosen = [MODES.get(metric(results, s, "on_leader_loss"), "") for s in followers]
    reacted = [metric(results, s, "mode_after_loss") for s in followers]
    tracks = Tracks([r["track"] for r in results if r is not None])
    return {
        "notice_time_max_s": max((t - killed_at if t is not None else float("inf")) for t in lost),
        "oldest_followed_max_s": max(metric(results, s, "oldest_followed_s") for s in followers),
        "reacted_as_chosen": reacted == chosen,
        "hold_drift_max_m": max((d for d in drifts if d is not None), default=0.0),
        "min_separation_m": tracks.min_separation(),
        "followers_landed_and_disarmed": all(metric(results, s, "landed_and_disarmed") for s in followers),
    }


SCENARIO = swarm_flight.swarm_scenario(
    "swarm_leader_loss",
    "The swarm_formation flight, its leader killed mid-box: the followers notice within 1 s and hold (or land)",
    script,
    evaluate_swarm,
    (
        Check("notice_time_max_s", 1.0),
        Check("oldest_followed_max_s", formation.LEADER_TIMEOUT_S),
        Check("reacted_as_chosen", True),
        Check("hold_drift_max_m", 0.5),
        Check("min_separation_m", 3.0, at_least=True),
        Check("followers_landed_and_disarmed", True),
    ),
)
