"""A ``stack fly`` scenario flown in one process (:class:`stack.runtime.inprocess.InProcessStack`).

The profile is prepared as ``stack fly`` prepares it (the scenario's parameters, ``--wind``, the
scenario module with its limits), so a seed flies the same flight, message for message, as
``stack fly SCENARIO --seed SEED``; it takes no processes, no bus and no lockstep protocol. Hence
the ceiling of the lockstep benchmark, :func:`ceiling_us_per_step`: the CPU time a step of the flight
costs when the same modules are chained in one process.
"""

from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stack.runtime.inprocess import InProcessStack
from stack.runtime.membus import PublishedMessage
from stack.scenario.flight import WIND_SPEED, prepare_flight
from stack.supervisor.profile import DEFAULT_PROFILE, Profile, load_profile


@dataclass(frozen=True)
class InProcessFlight:
    result: dict[str, Any]  # what the scenario module wrote (see stack.scenario.module)
    end_us: int  # the simulated time of the scenario's last tick
    steps: int
    step_cpu_s: float
    published: list[PublishedMessage]  # empty unless recorded
    refused: dict[str, int]  # messages the modules' inputs refused (stack.runtime.inputs), by module:topic

    @property
    def cpu_us_per_step(self) -> float:
        return self.step_cpu_s / self.steps * 1e6


def flight_profile(
    scenario: str,
    result: Path,
    profile: str | Path = DEFAULT_PROFILE,
    seed: int | None = None,
    wind: bool = False,
    wind_speed: float = WIND_SPEED,
) -> Profile:
    """The profile ``stack fly SCENARIO [--seed] [--wind-speed]`` runs (without its observers); the scenario
    writes its result to ``result``."""
    prof = load_profile(profile)
    if seed is not None:
        prof.seed = seed
    prepare_flight(prof, scenario, result, wind, wind_speed)
    return prof


def fly_in_process(
    scenario: str,
    profile: str | Path = DEFAULT_PROFILE,
    seed: int | None = None,
    *,
    wind: bool = False,
    record: bool = False,
    wire: bool = True,
    wind_speed: float = WIND_SPEED,
) -> InProcessFlight:
    """Fly a scenario in this process (``record``: keep every published message)."""
    with tempfile.TemporaryDirectory(prefix="stack-inprocess-") as tmp:
        result = Path(tmp) / "scenario_result.json"
        prof = flight_profile(scenario, result, profile, seed, wind, wind_speed)
        stack = InProcessStack(prof, wire=wire, record=record)
        stack.run()
        if not result.exists():
            raise RuntimeError(f"scenario {scenario} ended at t={stack.now_us / 1e6:.3f} s without a result")
        return InProcessFlight(
            json.loads(result.read_text()),
            stack.now_us,
            stack.steps,
            stack.step_cpu_s,
            stack.published,
            stack.refused(),
        )


def ceiling_us_per_step(
    scenario: str = "takeoff_land", profile: str | Path = DEFAULT_PROFILE, seed: int | None = None, wire: bool = True
) -> float:
    """CPU µs per lockstep step of the scenario flown in one process (process time over its steps);
    ``wire=False``: without encoding and decoding the messages."""
    return fly_in_process(scenario, profile, seed, wire=wire).cpu_us_per_step
