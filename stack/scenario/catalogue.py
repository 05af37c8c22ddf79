"""The scenarios ``stack fly`` knows: each a script, the topics it records, and how it is judged."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from stack.msg.topic import Topic
from stack.names import suggestion
from stack.scenario.script import Script, ScriptContext

Evaluate = Callable[[ScriptContext], dict[str, Any]]


@dataclass(frozen=True)
class Check:
    """A metric compared with a limit: ``metric <= limit`` (``at_least``: ``>=``; bool: must equal)."""

    metric: str
    limit: float | bool | str
    at_least: bool = False

    def passed(self, value: Any) -> bool:
        if isinstance(self.limit, bool | str):
            return value == self.limit
        if value is None or value != value:
            return False
        return value >= self.limit if self.at_least else value <= self.limit


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    script: Script
    evaluate: Evaluate
    checks: tuple[Check, ...]
    record: tuple[Topic, ...] = ()
    publish: tuple[Topic, ...] = ()
    watch: tuple[Topic, ...] = ()
    timeout_s: float = 300.0
    params: dict[str, Any] = field(default_factory=dict)
    profile: str | None = None
    """The launch profile the scenario flies on unless one is given, when the default one cannot fly it
    (link_loss: a simulated Pixhawk; the plane's scenarios: sitl_plane) or is not what its checks are sized for
    (rpyt_step: RotorS' controller on its default vehicle, the Firefly)."""
    options: dict[str, str] = field(default_factory=dict)
    """What a vehicle's profile may choose for the flight, with the defaults (``[scenario.plane_mission]
    mission = "c172_rectangle"``: a mission sized for that aircraft)."""
    choices: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """The values an option may take, for those that take few (a profile giving another is refused)."""
    swarm: Swarm | None = None
    """A scenario of several vehicles (``stack fly NAME --vehicles N``), or None for one of one vehicle."""

    @property
    def all_checks(self) -> tuple[Check, ...]:
        """Every check a profile may set a limit of: each vehicle's and, for a swarm scenario, the swarm's."""
        return self.checks + (self.swarm.checks if self.swarm is not None else ())


@dataclass(frozen=True)
class Swarm:
    """What a swarm scenario adds: what the other vehicles hear from the leader (vehicle 1), and how the swarm's
    flight is judged from every vehicle's result (each with its ground-truth track, stack.scenario.swarm_track)."""

    peers: tuple[Topic, ...]
    """The leader's topics each other vehicle reads, ``peer_delay_s`` after the leader published them."""
    peer_delay_s: float
    evaluate: Callable[[list[dict[str, Any]], float], dict[str, Any]]
    """The swarm's metrics from the vehicles' results (by vehicle; None for one that wrote none) and the spacing of
    their homes."""
    checks: tuple[Check, ...]
    min_vehicles: int = 2


def scenarios() -> dict[str, Scenario]:
    from stack.scenario import (
        attitude_step,
        failsafes,
        gps_loss,
        link_loss,
        mission_box,
        module_kill,
        plane_gps_loss,
        plane_loiter_wind,
        plane_mission,
        rpyt_step,
        swarm_formation,
        swarm_leader_loss,
        takeoff_land,
    )

    flights = (
        attitude_step, takeoff_land, mission_box, gps_loss, failsafes, link_loss, module_kill, rpyt_step, plane_mission,
        plane_loiter_wind, plane_gps_loss, swarm_formation, swarm_leader_loss,
    )
    return {s.name: s for s in (f.SCENARIO for f in flights)}


def get_scenario(name: str) -> Scenario:
    known = scenarios()
    if name not in known:
        raise KeyError(unknown_scenario(name))
    return known[name]


def unknown_scenario(name: str) -> str:
    known = sorted(scenarios())
    return f"unknown scenario '{name}'{suggestion(name, known)} (known: {', '.join(known)})"
