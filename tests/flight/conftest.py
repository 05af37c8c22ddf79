"""Flights shared by this directory's tests: each is flown once per test run, by whichever worker asks first.

Recording does not change a lockstep flight (the recorder never joins the lockstep), so one recorded
flight serves the report checks, the determinism checks and the in-process comparison.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests.flight.flights import Flight, InProcessFlight, fly_inprocess, fly_scenario
from tests.support.once import key_dir, once


@pytest.fixture(scope="session")
def fly(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., Flight]:
    """``fly(seed, run=0, scenario="attitude_step", wind=False, transport="shm", profile="sitl_quad")``: ``stack
    fly`` of that scenario and seed, every module its own process unless the profile groups them (``run``
    tells repeated flights apart; ``wind`` flies ``--wind``; ``transport`` carries the lockstep's messages)."""

    def flight(
        seed: int,
        run: int = 0,
        scenario: str = "attitude_step",
        wind: bool = False,
        transport: str = "shm",
        profile: str = "sitl_quad",
    ) -> Flight:
        def work(home: Path) -> dict:
            done = fly_scenario(home, scenario, seed, profile=profile, wind=wind, transport=transport)
            return {"returncode": done.returncode, "output": done.output, "report": done.report}

        windy = "-wind" if wind else ""
        grouped = "" if profile == "sitl_quad" else f"-{profile}"
        key = f"fly-{scenario}-seed{seed}-run{run}{windy}-{transport}{grouped}"
        done = once(tmp_path_factory, key, work)
        recording = key_dir(tmp_path_factory, key) / "flight.mcap"
        return Flight(done["returncode"], done["output"], done["report"], recording)

    return flight


@pytest.fixture(scope="session")
def fly_here(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., InProcessFlight]:
    """``fly_here(scenario, seed, profile="sitl_quad", wind=False)``: the scenario flown in one process (the
    ``stack fly`` flight, message for message), once per test run."""

    def flight(scenario: str, seed: int, profile: str = "sitl_quad", wind: bool = False) -> InProcessFlight:
        key = f"inprocess-{scenario}-{profile}-seed{seed}{'-wind' if wind else ''}"
        report = once(tmp_path_factory, key, lambda d: fly_inprocess(d, scenario, seed, profile, wind).report)
        return InProcessFlight(report, key_dir(tmp_path_factory, key) / "published.msgpack")

    return flight
