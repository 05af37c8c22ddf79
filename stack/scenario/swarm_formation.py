"""Scenario ``swarm_formation``: N vehicles take off together and fly the leader's box abreast, then land.

Vehicle 1 leads (stack.scenario.swarm_flight); each other vehicle keeps its place ``(i - 1) × spacing`` east of it
from the leader's position heard over the bus. Judged from the vehicles' ground truth in one frame
(stack.scenario.swarm_track): each follower's distance from its place while the leader flies the box (RMS and
worst), the closest any two vehicles came, and that every one landed and disarmed.
"""

from __future__ import annotations

from typing import Any

from stack.scenario import formation, swarm_flight
from stack.scenario.catalogue import Check
from stack.scenario.swarm_track import Tracks, metric, rms


def evaluate_swarm(results: list[dict[str, Any] | None], spacing_m: float) -> dict[str, Any]:
    if any(r is None for r in results):
        missing = [i + 1 for i, r in enumerate(results) if r is None]
        raise ValueError(f"vehicles {missing} wrote no result")
    tracks = Tracks([r["track"] for r in results if r is not None])
    t0, t1 = metric(results, 1, "box_start_at"), metric(results, 1, "box_end_at")
    if t0 is None or t1 is None:
        raise ValueError("the leader did not fly its box")
    errors = [
        e
        for slot in range(2, len(results) + 1)
        for e in tracks.formation_errors(slot - 1, formation.slot_offset(slot, spacing_m), t0, t1)
    ]
    return {
        "formation_error_rms_m": rms(errors),
        "formation_error_max_m": max(errors, default=float("nan")),
        "min_separation_m": tracks.min_separation(),
        "all_landed_and_disarmed": all(metric(results, s, "landed_and_disarmed") for s in range(1, len(results) + 1)),
        "box_time_s": t1 - t0,
    }


SCENARIO = swarm_flight.swarm_scenario(
    "swarm_formation",
    "N vehicles (--vehicles N) take off together, fly a 20 m box abreast of the leader, return and land",
    swarm_flight.script,
    evaluate_swarm,
    (
        Check("formation_error_rms_m", 0.4),
        Check("formation_error_max_m", 1.0),
        Check("min_separation_m", 3.0, at_least=True),
        Check("all_landed_and_disarmed", True),
    ),
)
