"""`stack cmd` flying the default profile from the command line as the README shows it: take off, go somewhere,
fly a mission, return, land, with --wait and its default timeouts (sized to each action, simulated time);
`stack status`'s vehicle summary; and --wait failing when a failsafe takes over."""

import json

import pytest

from tests.support.harness import default_stack, takeoff_when_ready

pytestmark = pytest.mark.flight


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    # The link-loss test stands in for a ground station's heartbeat on telemetry_status, the MAVLink link's topic.
    yield from default_stack(tmp_path_factory.mktemp("cmd_flight") / "home", open_topics=("telemetry_status",))


def local_position(stack) -> dict:
    out = stack.cli("topic", "echo", "vehicle_local_position", "-n", "1", "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_takeoff_goto_land_from_the_command_line(stack):
    takeoff = takeoff_when_ready(stack, "--alt", "3")
    assert takeoff.returncode == 0, takeoff.stderr
    lines = takeoff.stdout.splitlines()
    assert lines[0] == "takeoff: accepted" and lines[-1].startswith("takeoff complete: altitude ")
    home = json.loads(stack.cli("topic", "echo", "home_position", "-n", "1", "--json").stdout)
    assert local_position(stack)["z"] == pytest.approx(home["z"] - 3.0, abs=1.0)

    status = json.loads(stack.cli("status", "--json").stdout)["vehicle_summary"]
    summary = (status["mode"], status["armed"], status["failsafe"], status["failsafe_action"])
    assert summary == ("Hold", True, False, "none")
    assert status["position"]["altitude_above_home"] == pytest.approx(3.0, abs=1.0)
    assert status["battery"]["remaining"] > 0.5
    text = stack.cli("status").stdout.splitlines()
    assert text[1] == "vehicle: Hold, armed, failsafe: no" and text[2].startswith("position: N ")

    # Negative numbers are values, not options.
    goto = stack.cli("cmd", "goto", str(home["x"] - 5.0), str(home["y"]), str(home["z"] - 3.0), "--wait")
    assert goto.returncode == 0, goto.stderr
    assert goto.stdout.splitlines()[-1].startswith("goto: reached (")
    assert local_position(stack)["x"] == pytest.approx(home["x"] - 5.0, abs=1.0)

    land = stack.cli("cmd", "land", "--wait", timeout=300)
    assert land.returncode == 0, land.stderr
    assert land.stdout.splitlines()[-1] == "land: landed and disarmed"
    status = json.loads(stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--json").stdout)
    assert status["arming_state"] == 1  # disarmed after the landing


def test_the_readme_mission_and_a_return_from_high_up(stack):
    mission = stack.cli("cmd", "mission", "box", "--wait", timeout=600)  # as the README shows it
    assert mission.returncode == 0, mission.stderr
    lines = mission.stdout.splitlines()
    assert lines[-1] == "mission finished, landed and disarmed"
    assert any(line.startswith("item 6/6, ") for line in lines), lines

    assert takeoff_when_ready(stack, "--alt", "29").returncode == 0
    rtl = stack.cli("cmd", "rtl", "--wait", timeout=600)
    assert rtl.returncode == 0, rtl.stderr
    assert rtl.stdout.splitlines()[-1].startswith("rtl: landed at home (")


def test_takeoff_wait_fails_when_a_failsafe_takes_over(stack):
    # One ground-station heartbeat, then none: the link is lost COM_DL_LOSS_T later, during the takeoff.
    now = stack.cli("topic", "echo", "vehicle_status", "-n", "1", "--field", "timestamp").stdout.strip()
    heartbeat = stack.cli("topic", "pub", "telemetry_status", f'{{"timestamp": {now}, "heartbeat_type_gcs": true}}')
    assert heartbeat.returncode == 0, heartbeat.stderr
    takeoff = stack.cli("cmd", "takeoff", "--alt", "40", "--wait", timeout=300)
    assert takeoff.returncode == 1, (takeoff.stdout, takeoff.stderr)
    assert takeoff.stderr.strip().startswith("error: takeoff failed: a failsafe took over (")
    assert "gcs_connection_loss" in takeoff.stderr and "takeoff complete" not in takeoff.stdout
