"""`stack cmd` with a stand-in navigator and a fixed position estimate added to the first-flight stack: the
mission upload protocol end to end, missions placed about the vehicle's home, and --wait."""

import json
import re

import msgspec
import pytest

from stack.mathlib.geo import MapProjection
from stack.mission.items import Mission
from stack.mission.transfer import MAX_ITEMS, mission_from_message
from stack.msg import navigation
from tests.support.harness import REPO, RunningStack, attitude_only_profile, wait_no_processes

PLAN = REPO / "tests" / "mission" / "data" / "square.plan"
PLANNED_HOME = (47.3977419, 8.5455938, 488.0)
VEHICLE = (47.3986419, 8.5455938, 490.0)
"""Where the stand-in estimate puts the vehicle: 100 m north of the plan's planned home and 2 m higher."""


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cmd_mission")
    received = tmp / "received.jsonl"
    lat, lon, alt = VEHICLE
    profile = attitude_only_profile(
        tmp / "with_navigator.toml",
        f"""
[[module]]
module = "tests.cli.standins:FixedPosition"
args = {{ lat = {lat}, lon = {lon}, alt = {alt} }}

[[module]]
module = "tests.cli.standins:MissionResponder"
args = {{ out = "{received}" }}
""",
    )
    running = RunningStack(tmp / "home", profile, "--quiet")
    running.received = received
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(tmp / "home")


def last_received(stack) -> Mission:
    """The last mission the stand-in navigator received."""
    line = stack.received.read_text().splitlines()[-1]
    return mission_from_message(msgspec.msgpack.decode(bytes.fromhex(line), type=navigation.Mission))


def test_a_waypoint_list_is_accepted_by_the_navigator(stack, tmp_path):
    waypoints = tmp_path / "square.txt"
    waypoints.write_text("takeoff 5\n10 0 -5\n10 10 -5 90\nland\n")
    out = stack.cli("cmd", "mission", str(waypoints), "--no-start")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith("home: 47.3986419, 8.5455938, 490.0 m AMSL (")
    assert lines[1:] == ["mission accepted: 4 items"]
    mission = last_received(stack)
    assert mission.source == str(waypoints) and (mission.home.lat, mission.home.lon, mission.home.alt) == VEHICLE
    assert [(i.command, *i.position) for i in mission.items[1:3]] == [(16, 10.0, 0.0, -5.0), (16, 10.0, 10.0, -5.0)]


def test_a_plan_is_placed_about_the_vehicle_home_not_its_planned_home(stack):
    out = stack.cli("cmd", "mission", str(PLAN), "--no-start")
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-1] == "mission accepted: 6 items"
    takeoff, wp1, _speed, _wp2, wp3, _rtl = last_received(stack)
    projection = MapProjection(VEHICLE[0], VEHICLE[1])
    north, east = projection.project(PLANNED_HOME[0], PLANNED_HOME[1])
    assert north == pytest.approx(-100.07, abs=0.01)
    assert takeoff.position == pytest.approx((north, east, -15.0), abs=1e-6)
    assert (wp1.north, wp1.down) == pytest.approx((north + 20.0, -15.0), abs=0.02)
    assert wp3.down == pytest.approx(VEHICLE[2] - 510.0)  # an AMSL altitude, about the vehicle's home


def test_an_empty_mission_is_rejected_with_the_navigators_reason(stack, tmp_path):
    empty = tmp_path / "empty.plan"
    plan = json.loads(PLAN.read_text())
    plan["mission"]["items"] = []
    empty.write_text(json.dumps(plan))
    out = stack.cli("cmd", "mission", str(empty), "--no-start")
    assert out.returncode == 1 and "accepted" not in out.stdout
    assert out.stderr.strip() == "error: mission rejected: the mission has no items"
    assert len(last_received(stack)) == 0


def test_a_mission_longer_than_a_mission_may_be_is_refused_saying_so(stack, tmp_path):
    # The longest mission crosses the bus (one message, each float field 8 bytes wide); one more item is refused
    # before anything is sent, where a mission too large for the bus used to be lost on the way.
    longest = tmp_path / "longest.txt"
    longest.write_text("".join(f"{i % 20} {i // 20} -{1 + i % 7}.123456789 33.3 1.5 0.75\n" for i in range(MAX_ITEMS)))
    out = stack.cli("cmd", "mission", str(longest), "--no-start")
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-1] == f"mission accepted: {MAX_ITEMS} items"
    assert len(last_received(stack)) == MAX_ITEMS
    for count in (MAX_ITEMS + 1, 100_000):
        huge = tmp_path / f"huge_{count}.txt"
        huge.write_text("".join(f"{i % 20} {i // 20 % 20} -5\n" for i in range(count)))
        out = stack.cli("cmd", "mission", str(huge), "--no-start")
        assert out.returncode == 2 and "accepted" not in out.stdout
        assert out.stderr.strip() == (
            f"error: {huge}: mission refused: {count} items, more than the {MAX_ITEMS} a mission may have; nothing sent"
        )
    assert len(last_received(stack)) == MAX_ITEMS


def test_land_wait_follows_the_vehicle_until_disarmed(stack):
    # Never having taken off, the vehicle disarms COM_DISARM_PRFLT after arming: its longest (20 s
    # simulated), so that the land command reaches the vehicle still armed on a loaded machine.
    # A machine loaded enough to spend those between the two commands is told so; then they are sent again.
    assert stack.cli("param", "set", "COM_DISARM_PRFLT", "20").returncode == 0
    for _ in range(5):
        assert stack.cli("cmd", "arm").stdout.strip() == "arm: accepted"
        out = stack.cli("cmd", "land", "--wait", timeout=180)
        if "Switching to Land is currently not possible: the vehicle is disarmed" not in out.stderr:
            break
    assert stack.cli("param", "reset", "COM_DISARM_PRFLT").returncode == 0
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "land: accepted" and lines[-1] == "land: landed and disarmed"
    # Sized to a landing from the ground (about the floor), counted on the vehicle's (simulated) clock.
    assert any(re.fullmatch(r"land: following, for at most 3\d s \(simulated time\)", line) for line in lines), lines
    progress = [line for line in lines[1:-1] if not line.startswith(("vehicle: ", "land: following"))]
    assert all(line == "altitude 0.0 m, Land" for line in progress), lines


def test_takeoff_wait_reports_a_takeoff_that_never_climbs(stack):
    # Nothing flies the vehicle (no position controller; the estimate is fixed), so it disarms on the ground.
    out = stack.cli("cmd", "takeoff", "--alt", "3", "--wait", timeout=180)
    assert out.returncode == 1
    assert out.stdout.splitlines()[0] == "takeoff: accepted"
    assert out.stderr.strip().startswith("error: takeoff failed: the vehicle disarmed"), out.stderr


def test_a_mission_is_started_after_its_upload(stack, tmp_path):
    waypoints = tmp_path / "out_and_back.txt"
    waypoints.write_text("takeoff 5\n10 0 -5\nland\n")
    beyond = stack.cli("cmd", "mission", str(waypoints), "--first", "3")
    assert beyond.returncode == 1
    assert beyond.stdout.splitlines()[-1] == "mission accepted: 3 items"
    assert beyond.stderr.strip() == "mission start: DENIED: Mission start: first item (param1) must be −1…2, got 3"
    out = stack.cli("cmd", "mission", str(waypoints))
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-2:] == ["mission accepted: 3 items", "mission start: accepted"]
