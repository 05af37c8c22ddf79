"""Every control module killed in turn during a lockstep hover; restarted, the flight goes on.

Simulated time waits while the supervisor restarts a dead module, so after each restart the vehicle must still
be armed, in Hold, where it was (the commander resumes from its kept state; mc_pos_control resumes flying, not
taking off). Flown here on one seed; ``benchmarks/sweep.py --scenarios module_kill --seeds 1-20`` flies it on more.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from stack.scenario.module_kill import MODULES
from stack.supervisor.profile import load_profile
from tests.flight.flights import Flight

pytestmark = pytest.mark.flight
# The chain's modules the default profile runs (not RotorS' controller and joystick interface).
RUNNING = [m for m in MODULES if m in {entry.name for entry in load_profile("sitl_quad").modules}]


def test_each_control_module_killed_in_a_hover_restarts_and_the_flight_goes_on(fly: Callable[..., Flight]) -> None:
    flight = fly(1, scenario="module_kill")
    report = flight.report
    assert report["error"] is None, flight.output
    assert report["passed"] is True and flight.returncode == 0, flight.output
    metrics = report["metrics"]
    assert metrics["modules_killed"] == len(RUNNING) and metrics["all_resumed"] is True
    assert metrics["max_deviation_m"] <= 0.5
    for module in RUNNING:
        assert f"{module} failed with exit code -9" in flight.output, module
        assert f"restarting {module} (restart 1)" in flight.output, module
    told = [m.msg.text for m in flight.messages("mavlink_log")]
    assert "Commander restarted: resuming armed in Hold" in told
    assert not any("control lost" in text for text in told), told
    assert "Traceback" not in flight.output
