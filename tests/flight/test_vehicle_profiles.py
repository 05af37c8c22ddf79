"""The attitude_step scenario passes on every vehicle model, each with its own launch profile.

Each profile flies once, in one process (the ``stack fly`` flight, message for message), and is judged by the
first-flight limits; the only one relaxed is the Firefly's yaw rise, which its profile derives from the
hexacopter's yaw authority.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.flight.flights import ATTITUDE_STEP_TARGETS as FIRST_FLIGHT_LIMITS
from tests.flight.flights import InProcessFlight

pytestmark = pytest.mark.flight

# launch/sitl_firefly.toml, [scenario.attitude_step]: the time-optimal yaw rise with the collective
# at hover is 0.296 s on the Firefly, as it is 0.199 s on the SIH quad the 0.20 s limit was set for.
OVERRIDES = {"sitl_firefly": {"yaw_rise_time_s": 0.30}}
PROFILES = ("sitl_hummingbird", "sitl_pelican", "sitl_firefly")


@pytest.fixture(params=PROFILES)
def profile(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.fixture
def report(profile: str, fly_here: Callable[..., InProcessFlight]) -> dict:
    """attitude_step on seed 1 of PROFILE, flown once per test run."""
    return fly_here("attitude_step", 1, profile).report


def test_every_check_passed(report: dict) -> None:
    assert report["passed"] is True
    assert report["error"] is None
    assert [c["name"] for c in report["checks"] if not c["passed"]] == []


def test_judged_by_the_first_flight_limits(report: dict, profile: str) -> None:
    expected = {**FIRST_FLIGHT_LIMITS, **OVERRIDES.get(profile, {})}
    assert {c["name"]: c["limit"] for c in report["checks"]} == expected
