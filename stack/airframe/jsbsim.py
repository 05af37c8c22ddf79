"""A JSBSim aircraft as data: a ``type = "jsbsim"`` vehicle file (the aircraft JSBSim loads, the properties each
actuator output drives, the brakes, the allocator's airframe), read and checked without JSBSim itself."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

VEHICLE_TYPE = "jsbsim"
"""The ``type`` of a vehicle file this plant flies."""
CHANNELS = ("throttle", "aileron", "elevator", "rudder")
"""The plane's actuator outputs in order: output[0] throttle [0, 1], output[1..3] surfaces [−1, 1]."""

@dataclass(frozen=True, slots=True)
class ControlTarget:
    """One JSBSim property an actuator output drives: property = gain · output."""

    property: str
    gain: float


@dataclass(frozen=True, slots=True)
class Brakes:
    """Automatic wheel brakes: ``command`` on ``properties`` while the throttle is below ``below_throttle``
    and every ground contact touches."""

    properties: tuple[str, ...]
    command: float
    below_throttle: float


@dataclass(frozen=True, slots=True)
class JsbsimAircraft:
    """A JSBSim aircraft as the stack flies it (a ``type = "jsbsim"`` vehicle file)."""

    name: str
    description: str
    aircraft: str  # JSBSim model name (its packaged aircraft/<name>/<name>.xml)
    heading_deg: float  # initial heading, the runway's direction
    settle_time: float  # s on the brakes from the first guess to the ground equilibrium, before time 0
    ground_contacts: tuple[int, ...]  # gear units (gear/unit[i]) of the wheels
    initial_properties: Mapping[str, float]  # set once after the initial conditions, in order
    controls: tuple[tuple[ControlTarget, ...], ...]  # per channel of CHANNELS
    brakes: Brakes
    airframe: Mapping[str, float]
    path: str

    @property
    def input_count(self) -> int:
        """Actuator outputs the plant reads: one throttle and three surfaces."""
        return len(self.controls)

    @property
    def rotor_count(self) -> int:
        """Motors (PX4's CA_ROTOR_COUNT): the one propeller."""
        return int(self.airframe["CA_ROTOR_COUNT"])


class JsbsimParser:
    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, key: str, problem: str) -> ValueError:
        return ValueError(f"{self.path.name}: {key}: {problem}")

    def table(self, data: Mapping[str, Any], key: str, allowed: set[str] | None) -> Mapping[str, Any]:
        value = data.get(key)
        if not isinstance(value, dict):
            raise self.error(key, "expected a table")
        for k in value:
            if allowed is not None and k not in allowed:
                raise self.error(f"{key}.{k}", "unknown key")
        return value

    def string(self, data: Mapping[str, Any], key: str, where: str) -> str:
        value = data.get(key)
        if not isinstance(value, str) or not value:
            raise self.error(where, "expected a non-empty string")
        return value

    def number(self, value: Any, where: str, lo: float = -math.inf, hi: float = math.inf) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise self.error(where, "expected a finite number")
        if not lo <= value <= hi:
            raise self.error(where, f"must be in [{lo:g}, {hi:g}], got {value}")
        return float(value)

    def aircraft(self, data: Mapping[str, Any]) -> JsbsimAircraft:
        for k in data:
            if k not in ("name", "description", "type", "jsbsim", "controls", "brakes", "airframe"):
                raise self.error(k, "unknown key")
        if data.get("type") != VEHICLE_TYPE:
            raise self.error("type", f'expected "{VEHICLE_TYPE}" for a JSBSim aircraft')
        sim = self.table(data, "jsbsim", {"aircraft", "heading_deg", "settle_time", "ground_contacts", "set"})
        contacts = sim.get("ground_contacts")
        if (
            not isinstance(contacts, list)
            or not contacts
            or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in contacts)
        ):
            raise self.error("jsbsim.ground_contacts", "expected a non-empty list of gear unit indices")
        initial = self.table(sim, "set", None) if "set" in sim else {}
        initial_properties = {k: self.number(v, f"jsbsim.set.{k}") for k, v in initial.items()}
        return JsbsimAircraft(
            name=self.string(data, "name", "name"),
            description=self.string(data, "description", "description"),
            aircraft=self.string(sim, "aircraft", "jsbsim.aircraft"),
            heading_deg=self.number(sim.get("heading_deg", 0.0), "jsbsim.heading_deg", -360.0, 360.0),
            settle_time=self.number(sim.get("settle_time"), "jsbsim.settle_time", 0.0, 60.0),
            ground_contacts=tuple(contacts),
            initial_properties=MappingProxyType(initial_properties),
            controls=self.controls(data),
            brakes=self.brakes(data),
            airframe=self.airframe(data),
            path=str(self.path),
        )

    def controls(self, data: Mapping[str, Any]) -> tuple[tuple[ControlTarget, ...], ...]:
        table = self.table(data, "controls", set(CHANNELS))
        channels = []
        for channel in CHANNELS:
            where = f"controls.{channel}"
            entries = table.get(channel)
            if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
                raise self.error(where, "expected a list of {property, gain} tables")
            targets = []
            for i, entry in enumerate(entries):
                if set(entry) != {"property", "gain"}:
                    raise self.error(f"{where}[{i}]", "expected exactly the keys property and gain")
                targets.append(
                    ControlTarget(self.string(entry, "property", f"{where}[{i}].property"),
                                  self.number(entry["gain"], f"{where}[{i}].gain"))
                )
            channels.append(tuple(targets))
        return tuple(channels)

    def brakes(self, data: Mapping[str, Any]) -> Brakes:
        table = self.table(data, "brakes", {"properties", "command", "below_throttle"})
        properties = table.get("properties")
        if not isinstance(properties, list) or not all(isinstance(p, str) and p for p in properties):
            raise self.error("brakes.properties", "expected a list of property names")
        return Brakes(
            properties=tuple(properties),
            command=self.number(table.get("command"), "brakes.command", 0.0, 1.0),
            below_throttle=self.number(table.get("below_throttle"), "brakes.below_throttle", 0.0, 1.0),
        )

    def airframe(self, data: Mapping[str, Any]) -> Mapping[str, float]:
        table = self.table(data, "airframe", None)
        params = {k: self.number(v, f"airframe.{k}") for k, v in table.items()}
        for key, expected in (("CA_AIRFRAME", 1.0), ("CA_ROTOR_COUNT", 1.0)):
            if params.get(key) != expected:
                raise self.error(f"airframe.{key}", f"must be {expected:g} for a plane with one motor")
        return MappingProxyType(params)
