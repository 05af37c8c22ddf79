"""The fixed-wing stack flies the SIH airplane from runway to runway, on L1 and on NPFG.

plane_mission (runway takeoff, a 300–400 m rectangle at 40 m, two loiter circles, return and landing) on L1, and
plane_loiter_wind (three circles in an 8 m/s wind with gusts) on NPFG, each on its own seed, judged by the
scenarios' limits (doubled in wind); and plane_mission on JSBSim's Cessna 172P with the mission its profile
chooses (legs of 1.5–1.8 km), judged as the SIH airplane's but for its loiter and touchdown; and plane_gps_loss:
20 s without GPS while circling, the position estimate dead-reckoning on the airspeed. These fly in one process
(the ``stack fly`` flight, message for message); the plane's stack also comes up as processes, one per module.
benchmarks/sweep.py flies 20 seeds of each on either guidance, calm and in 8 m/s wind.
"""

from __future__ import annotations

import json
from collections.abc import Callable

import pytest

from stack.msg.fixedwing import PositionSetpoint
from tests.flight.flights import InProcessFlight
from tests.support.harness import RunningStack, eventually, wait_no_processes

pytestmark = pytest.mark.flight


@pytest.mark.parametrize(
    ("scenario", "profile", "seed"),
    [
        ("plane_mission", "sitl_plane", 1),
        ("plane_loiter_wind", "sitl_plane_npfg", 2),
        ("plane_mission", "jsbsim_c172", 3),
    ],
)
def test_the_plane_flies_its_scenarios_within_their_limits(
    fly_here: Callable[..., InProcessFlight], scenario: str, profile: str, seed: int
) -> None:
    report = fly_here(scenario, seed, profile).report
    assert report["error"] is None, report
    assert [c["name"] for c in report["checks"] if not c["passed"]] == [], report["metrics"]
    assert report["passed"] is True, report
    metrics = report["metrics"]
    assert metrics["landed_and_disarmed"] is True
    assert abs(metrics["landing_offset_m"]) <= 10.0


def test_without_gps_the_plane_dead_reckons_on_its_airspeed(fly_here: Callable[..., InProcessFlight]) -> None:
    flight = fly_here("plane_gps_loss", 4, "sitl_plane")
    report = flight.report
    assert report["error"] is None, report
    assert report["passed"] is True, report
    positions = flight.messages("vehicle_local_position")
    assert any(m.msg.dead_reckoning for m in positions) and not positions[-1].msg.dead_reckoning
    # The plane's own topics are published, nested setpoints included.
    triplets = flight.messages("position_setpoint_triplet")
    assert any(m.msg.current.type == PositionSetpoint.SETPOINT_TYPE_LOITER for m in triplets)
    assert flight.messages("airspeed_validated") and flight.messages("wind")


def test_the_planes_stack_runs_as_processes(tmp_path) -> None:
    """``stack up sitl_plane``: every module its own process, each running, the airspeed and the position estimated."""
    home = tmp_path / "home"
    stack = RunningStack(home, "sitl_plane", "--quiet", "--speed", "4")
    try:
        stack.wait_up()
        modules = {m["module"]: m for m in stack.status()["modules"]}
        assert {"fw_att_control", "fw_pos_control", "airspeed_selector", "navigator"} <= modules.keys(), modules

        def estimated() -> bool:
            out = stack.cli("topic", "echo", "vehicle_local_position", "-n", "1", "--json")
            return out.returncode == 0 and json.loads(out.stdout.splitlines()[0])["xy_valid"]

        eventually(estimated, 60.0, "a valid position estimate")
        airspeed = stack.cli("topic", "echo", "airspeed_validated", "-n", "1", "--json")
        assert airspeed.returncode == 0, airspeed.stderr
        assert all(m["state"] == "running" for m in stack.status()["modules"]), stack.status()
    finally:
        assert stack.stop() == 0, stack.output
    assert "Traceback" not in stack.output
    assert not wait_no_processes(home)
