"""`stack cmd` flying the default profile from the command line: take off, go somewhere, land, with --wait."""

import json
import time

import pytest

from tests.support.harness import REPO, RunningStack, wait_no_processes

pytestmark = pytest.mark.flight


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    home = tmp_path_factory.mktemp("cmd_flight") / "home"
    running = RunningStack(home, REPO / "launch" / "sitl_quad.toml", "--quiet")
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(home)


def local_position(stack) -> dict:
    out = stack.cli("topic", "echo", "vehicle_local_position", "-n", "1", "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_takeoff_goto_land_from_the_command_line(stack):
    # Arming waits for the position estimate; the commander says so until then.
    deadline = time.monotonic() + 120.0
    while True:
        takeoff = stack.cli("cmd", "takeoff", "--alt", "3", "--wait", "--timeout", "120")
        if takeoff.returncode == 0 or time.monotonic() > deadline:
            break
        assert "local position" in takeoff.stderr or "GPS" in takeoff.stderr, takeoff.stderr
        time.sleep(1.0)
    assert takeoff.returncode == 0, takeoff.stderr
    assert takeoff.stdout.splitlines()[0] == "takeoff: accepted"
    home = json.loads(stack.cli("topic", "echo", "home_position", "-n", "1", "--json").stdout)
    assert local_position(stack)["z"] == pytest.approx(home["z"] - 3.0, abs=0.5)

    goto = stack.cli(
        "cmd", "goto", str(home["x"] + 5.0), str(home["y"]), str(home["z"] - 3.0), "--wait", "--timeout", "120"
    )
    assert goto.returncode == 0, goto.stderr
    here = local_position(stack)
    assert here["x"] == pytest.approx(home["x"] + 5.0, abs=1.0)

    land = stack.cli("cmd", "land", "--wait", "--timeout", "180")
    assert land.returncode == 0, land.stderr
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    assert status["arming_state"] == 1  # disarmed after the landing
