"""Multi-process flights shared by this directory's tests: each (seed, run) is flown once per session.

Recording does not change a lockstep flight (the recorder never joins the lockstep), so one
recorded flight serves the report checks, the determinism checks and the in-process comparison.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.flight.flights import Flight, fly_scenario


@pytest.fixture(scope="session")
def fly(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., Flight]:
    """``fly(seed, run=0, scenario="attitude_step", wind=False, transport="shm")``: the flight of that
    scenario and seed on the default profile (``run`` tells repeated flights apart; ``wind`` flies
    ``--wind``; ``transport`` carries the lockstep's messages)."""
    flights: dict[tuple[str, int, int, bool, str], Flight] = {}

    def flight(
        seed: int, run: int = 0, scenario: str = "attitude_step", wind: bool = False, transport: str = "shm"
    ) -> Flight:
        key = (scenario, seed, run, wind, transport)
        if key not in flights:
            windy = "-wind" if wind else ""
            home = tmp_path_factory.mktemp(f"fly-{scenario}-seed{seed}-run{run}{windy}-{transport}")
            flights[key] = fly_scenario(home, scenario, seed, wind=wind, transport=transport)
        return flights[key]

    return flight
