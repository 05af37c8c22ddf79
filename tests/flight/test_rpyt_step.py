"""RotorS' roll-pitch-yawrate-thrust controller flies the RotorS profiles.

rpyt_step flies steps of roll, pitch and yaw rate through the RotorS mode's sticks on each RotorS profile (a seed
each), judged by the limits of its profile; RotorS' law has no integrator, so the yaw rate settles short of the
command by the rotors' drag torque over the yaw-rate gain, which the vehicle model predicts. The default profile
flies the same steps with PX4's loops. These figures come from flights in one process (the ``stack fly`` flight,
message for message), as does takeoff_land, which holds the default limits in PX4's auto modes flown by RotorS'
controller.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from stack.airframe.model import load_vehicle
from stack.params import catalogue
from stack.scenario.catalogue import scenarios
from stack.supervisor.profile import load_profile
from tests.flight.flights import InProcessFlight

pytestmark = pytest.mark.flight

# Each profile flies its own seed, so the suite flies three (benchmarks/sweep.py flies 20 on each).
PROFILE_SEEDS = (("rotors_firefly", 1), ("rotors_hummingbird", 2), ("rotors_pelican", 3))
FlyHere = Callable[..., InProcessFlight]


def _param(entry, name: str) -> float:
    return float(entry.params.get(name, catalogue.get(name).default))


def predicted_yaw_rate_error_dps(profile: str) -> float:
    """r·c/(K_ω,z + c): the steady yaw rate ω balances K_ω,z·(r − ω) against the drag torque c·ω, where
    c = k_D·Σω_i·l_i² (each hub, l_i from the centre, moves at ω·l_i against its rotor's H-force k_D·ω_i·v)
    at the hover rotor speed ω_i = ω_max·√(hover thrust fraction)."""
    modules = {entry.name: entry for entry in load_profile(profile).modules}
    controller = modules["roll_pitch_yawrate_thrust_controller"]
    vehicle = load_vehicle(str(controller.args["vehicle"]))
    rotor_speed = vehicle.motor.max_rotor_speed * vehicle.hover_command
    drag = vehicle.motor.rotor_drag_coefficient * rotor_speed * sum(r.position[0] ** 2 + r.position[1] ** 2
                                                                   for r in vehicle.rotors)
    gain = _param(controller, "RPYT_RATE_GAIN_Z")
    return _param(modules["rotors_joy_interface"], "RJOY_YAWRATE_MAX") * drag / (gain + drag)


@pytest.mark.parametrize(("profile", "seed"), PROFILE_SEEDS)
def test_every_check_passed_by_the_profile_s_limits(fly_here: FlyHere, profile: str, seed: int) -> None:
    report = fly_here("rpyt_step", seed, profile).report
    assert report["error"] is None, report
    assert [c["name"] for c in report["checks"] if not c["passed"]] == [], report["metrics"]
    assert report["passed"] is True, report
    limits = {c["name"]: c["limit"] for c in report["checks"]}
    assert limits == {**limits, **load_profile(profile).scenario_limits.get("rpyt_step", {})}


def test_without_a_profile_rpyt_step_flies_the_vehicle_its_checks_are_sized_for() -> None:
    # `stack fly rpyt_step`, as the README shows it: RotorS' controller on the Firefly, flown above on seed 1.
    assert scenarios()["rpyt_step"].profile == PROFILE_SEEDS[0][0] == "rotors_firefly"


@pytest.mark.parametrize(("profile", "seed"), PROFILE_SEEDS)
def test_the_yaw_rate_falls_short_by_the_rotor_drag_over_the_rate_gain(
    fly_here: FlyHere, profile: str, seed: int
) -> None:
    metrics = fly_here("rpyt_step", seed, profile).report["metrics"]
    predicted = predicted_yaw_rate_error_dps(profile)
    assert metrics["yaw_rate_up_ss_error_dps"] == pytest.approx(predicted, rel=0.02)
    assert abs(metrics["yaw_rate_back_ss_error_dps"]) < 0.02 * predicted  # no drag without rotation
    for axis in ("roll", "pitch"):
        assert metrics[f"{axis}_up_rise_time_s"] > 0.0 and math.isfinite(metrics[f"{axis}_ss_error_deg"])


def test_takeoff_land_in_the_auto_modes_meets_the_default_limits(fly_here: FlyHere) -> None:
    report = fly_here("takeoff_land", 3, "rotors_pelican").report
    assert report["error"] is None, report
    assert report["profile"] == "rotors_pelican"
    assert report["passed"] is True, report
    assert report["metrics"]["landed_and_disarmed"] is True


def test_the_rotors_mode_on_px4s_attitude_loop_follows_the_sticks(fly_here: FlyHere) -> None:
    """The default profile flies the RotorS mode with PX4's attitude and rate loops: it follows roll and pitch
    faster than RotorS' law, and, holding a heading moved by the commanded rate, the yaw rate with no shortfall.
    (The RotorS profiles above fly seeds 1–3; this flies a fourth.)"""
    report = fly_here("rpyt_step", 4).report
    metrics = report["metrics"]
    assert report["error"] is None, report
    assert metrics["landed_and_disarmed"] is True
    for axis in ("roll", "pitch"):
        for step in ("up", "over", "back"):
            assert metrics[f"{axis}_{step}_rise_time_s"] < 0.15, (axis, step, metrics)
            assert abs(metrics[f"{axis}_{step}_ss_error_deg"]) < 1.0, (axis, step, metrics)
    assert metrics["yaw_rate_up_rise_time_s"] < 0.3
    assert abs(metrics["yaw_rate_up_ss_error_dps"]) < 1.0
