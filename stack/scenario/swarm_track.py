"""What a vehicle of a swarm flight reports beyond its own checks, and how the swarm is judged from those reports.

Each vehicle's result carries its ground-truth track: ``[t, lat, lon, alt]`` every TRACK_PERIOD_S of simulated
time. In lockstep every vehicle of a world steps at the same simulated times (stack.runtime.world_clock), so the
tracks share their times, and placed in one frame (north, east, down about the leader's first point) they give
the distances between vehicles at each instant.
"""

from __future__ import annotations

import itertools
import json
import math
from typing import Any

from stack.bus import keys
from stack.mathlib.geo import MapProjection
from stack.msg.registry import ORB_ID
from stack.scenario.script import ScriptContext, SwarmRole

TRACK_PERIOD_S = 0.1
Vec3 = tuple[float, float, float]


def swarm_role(text: str) -> SwarmRole:
    """The scenario module's ``swarm`` argument; ValueError when malformed."""
    value = json.loads(text)
    if not isinstance(value, dict) or set(value) != {"slot", "vehicles", "spacing_m"}:
        raise ValueError(f'swarm: {{"slot", "vehicles", "spacing_m"}} are wanted, not {text!r}')
    slot, vehicles, spacing = value["slot"], value["vehicles"], value["spacing_m"]
    names = isinstance(vehicles, list) and all(isinstance(v, str) and keys.valid_name(v) for v in vehicles)
    if not (names and vehicles):
        raise ValueError(f"swarm: vehicles must be a list of vehicle names, not {vehicles!r}")
    if not (isinstance(slot, int) and 1 <= slot <= len(vehicles)):
        raise ValueError(f"swarm: slot {slot!r} is not one of 1..{len(vehicles)}")
    if not (isinstance(spacing, int | float) and math.isfinite(spacing) and spacing > 0):
        raise ValueError(f"swarm: spacing_m must be a positive number, not {spacing!r}")
    return SwarmRole(slot, tuple(vehicles), float(spacing))


def swarm_track(ctx: ScriptContext) -> list[list[float]]:
    """The vehicle's true ``[t, lat, lon, alt]`` at each multiple of TRACK_PERIOD_S it has a sample for."""
    truth = ctx.series.get(ORB_ID.sim_groundtruth)
    if truth is None:
        return []
    track: list[list[float]] = []
    last = -1
    for t, m in zip(truth.times, truth.values, strict=True):
        tick = round(t / TRACK_PERIOD_S)
        if tick != last and abs(t - tick * TRACK_PERIOD_S) < 1e-6 and math.isfinite(m.lat):
            track.append([tick * TRACK_PERIOD_S, m.lat, m.lon, m.alt])
            last = tick
    return track


class Tracks:
    """The vehicles' tracks in one frame: north, east, down (m) about the leader's first point, by track tick."""

    def __init__(self, tracks: list[list[list[float]]]) -> None:
        if not tracks or not tracks[0]:
            raise ValueError("the leader's track is empty")
        _, lat0, lon0, alt0 = tracks[0][0]
        frame = MapProjection(lat0, lon0)
        self.by_tick: list[dict[int, Vec3]] = []
        for track in tracks:
            points = {}
            for t, lat, lon, alt in track:
                north, east = frame.project(lat, lon)
                points[round(t / TRACK_PERIOD_S)] = (north, east, alt0 - alt)
            self.by_tick.append(points)

    def formation_errors(self, follower: int, offset: Vec3, t0: float, t1: float) -> list[float]:
        """The distance of vehicle ``follower`` (0: the leader) from its place, ``offset`` from the leader, at each
        tick of [t0, t1] both have."""
        leader, own = self.by_tick[0], self.by_tick[follower]
        ticks = sorted(k for k in leader.keys() & own.keys() if t0 <= k * TRACK_PERIOD_S <= t1)
        errors = []
        for k in ticks:
            place = tuple(leader[k][i] + offset[i] for i in range(3))
            errors.append(math.dist(own[k], place))
        return errors

    def min_separation(self) -> float:
        """The smallest distance between any two vehicles at any tick both have (inf with fewer than two)."""
        closest = math.inf
        for a, b in itertools.combinations(self.by_tick, 2):
            for k in a.keys() & b.keys():
                closest = min(closest, math.dist(a[k], b[k]))
        return closest


def rms(values: list[float]) -> float:
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else math.nan


def metric(results: list[dict[str, Any] | None], slot: int, name: str) -> Any:
    """A metric of vehicle ``slot`` (1: the leader); None when it wrote no result or has no such metric."""
    result = results[slot - 1]
    return None if result is None else result.get("metrics", {}).get(name)
