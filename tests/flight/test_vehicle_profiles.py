"""Issue 3: the attitude_step scenario passes on every vehicle model, each with its own launch profile.

Each profile flies once, through the real CLI, and is judged by the issue's limits; the only one
relaxed is the Firefly's yaw rise, which its profile derives from the hexacopter's yaw authority.
"""

from __future__ import annotations

import pytest

from tests.flight.flights import ATTITUDE_STEP_TARGETS as ISSUE_LIMITS
from tests.flight.flights import Flight, fly_scenario

pytestmark = pytest.mark.flight

# launch/sitl_firefly.toml, [scenario.attitude_step]: the time-optimal yaw rise with the collective
# at hover is 0.296 s on the Firefly, as it is 0.199 s on the SIH quad the issue's 0.20 s was set for.
OVERRIDES = {"sitl_firefly": {"yaw_rise_time_s": 0.30}}
PROFILES = ("sitl_hummingbird", "sitl_pelican", "sitl_firefly")


@pytest.fixture(scope="module", params=PROFILES)
def profile(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.fixture(scope="module")
def flight(profile: str, tmp_path_factory: pytest.TempPathFactory) -> Flight:
    """``stack fly attitude_step --profile PROFILE``, flown once per profile."""
    return fly_scenario(tmp_path_factory.mktemp(f"fly-attitude_step-{profile}"), "attitude_step", 1, profile)


def test_every_check_passed(flight: Flight) -> None:
    assert flight.returncode == 0, flight.output
    assert flight.report["passed"] is True
    assert flight.report["error"] is None
    assert [c["name"] for c in flight.report["checks"] if not c["passed"]] == []
    assert "PASSED" in flight.output


def test_report_names_the_profile(flight: Flight, profile: str) -> None:
    assert flight.report["scenario"] == "attitude_step"
    assert flight.report["profile"] == profile


def test_judged_by_the_issue_limits(flight: Flight, profile: str) -> None:
    expected = {**ISSUE_LIMITS, **OVERRIDES.get(profile, {})}
    assert {c["name"]: c["limit"] for c in flight.report["checks"]} == expected
