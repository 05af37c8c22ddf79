"""Multi-process flights shared by this directory's tests: each (seed, run) is flown once per session.

Recording does not change a lockstep flight (the recorder never joins the lockstep), so one
recorded flight serves the report checks, the determinism checks and the in-process comparison.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.flight.flights import Flight, fly_attitude_step


@pytest.fixture(scope="session")
def fly(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., Flight]:
    """``fly(seed, run=0)``: the flight of that seed (``run`` tells repeated flights apart)."""
    flights: dict[tuple[int, int], Flight] = {}

    def flight(seed: int, run: int = 0) -> Flight:
        if (seed, run) not in flights:
            flights[(seed, run)] = fly_attitude_step(tmp_path_factory.mktemp(f"fly-seed{seed}-run{run}"), seed)
        return flights[(seed, run)]

    return flight
