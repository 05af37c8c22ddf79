"""Commands the default profile refuses, each with its reason and with the vehicle left as it was: a takeoff to
1e9 m, go-to targets a million kilometres away or underground, another system's command, an infinite DO_SET_MODE
and a manual mode without sticks in flight."""

import json
import time

import pytest

from tests.support.harness import default_stack

pytestmark = pytest.mark.flight

DISARMED, ARMED = 1, 2
HOLD = 4  # NAVIGATION_STATE_AUTO_LOITER


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    yield from default_stack(tmp_path_factory.mktemp("cmd_checks") / "home")


def status(stack) -> dict:
    out = stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def refusal(out) -> str:
    """The reason line of a refused ``stack cmd`` (exit code 1)."""
    assert out.returncode == 1, (out.stdout, out.stderr)
    assert "accepted" not in out.stdout
    return out.stderr.strip()


def commander_log_has(stack, text: str, timeout: float = 30.0) -> bool:
    log = stack.run_dir() / "commander.log"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if text in log.read_text():
            return True
        time.sleep(0.2)
    return False


def publish_command(stack, values: str) -> None:
    out = stack.cli("topic", "pub", "vehicle_command", values)
    assert out.returncode == 0, out.stderr


def test_on_the_ground(stack):
    line = refusal(stack.cli("cmd", "takeoff", "--alt", "1e9"))
    assert line == "takeoff: DENIED: Takeoff: 1000000000.0 m above home is outside MIS_TAKEOFF_ALT's range (0, 80] m"

    # A forced arm for system 99, then for component 191 of this one: neither is for this autopilot.
    publish_command(stack, '{"command": 400, "param1": 1, "param2": 21196, "target_system": 99}')
    publish_command(stack, '{"command": 400, "param1": 1, "param2": 21196, "target_component": 191}')
    publish_command(stack, '{"command": 176, "param1": 1e999, "param2": 1}')  # DO_SET_MODE, base mode +inf
    assert commander_log_has(stack, "Set mode: base mode (param1) must be 0–255, got inf")
    # The commander lives on and answers what follows; the arming commands were never answered nor obeyed.
    assert stack.cli("cmd", "mode", "hold").returncode == 0
    assert status(stack)["arming_state"] == DISARMED
    assert "command 400" not in (stack.run_dir() / "commander.log").read_text()


def test_in_flight(stack):
    deadline = time.monotonic() + 120.0
    while True:  # arming waits for the position estimate; the commander says so until then
        takeoff = stack.cli("cmd", "takeoff", "--alt", "3", "--wait", "--timeout", "120")
        if takeoff.returncode == 0 or time.monotonic() > deadline:
            break
        time.sleep(1.0)
    assert takeoff.returncode == 0, takeoff.stderr
    before = status(stack)
    assert (before["arming_state"], before["nav_state"]) == (ARMED, HOLD)

    far = refusal(stack.cli("cmd", "goto", "1e9", "0", "-5"))
    assert far.startswith("goto: DENIED: Reposition denied: target ")
    assert far.endswith("m from home, beyond MIS_DIST_1WP 900 m")
    ground = refusal(stack.cli("cmd", "goto", "0", "0", "1e9"))
    assert ground.startswith("goto: DENIED: Reposition denied: target -") and "it would fly into the ground" in ground
    acro = refusal(stack.cli("cmd", "mode", "acro"))
    assert acro == (
        "mode Acro: TEMPORARILY_REJECTED: Switching to Acro is currently not possible: no manual control input"
    )

    after = status(stack)
    assert (after["arming_state"], after["nav_state"], after["nav_state_user_intention"]) == (ARMED, HOLD, HOLD)
    assert after["nav_state_timestamp"] == before["nav_state_timestamp"]
    home = json.loads(stack.cli("topic", "echo", "home_position", "-n", "1", "--json").stdout)
    here = json.loads(stack.cli("topic", "echo", "vehicle_local_position", "-n", "1", "--json").stdout)
    assert abs(here["x"] - home["x"]) < 1.0 and abs(here["z"] - (home["z"] - 3.0)) < 0.5

    assert stack.cli("cmd", "land", "--wait", "--timeout", "180").returncode == 0
