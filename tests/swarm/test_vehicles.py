"""Several vehicles on one bus (two `stack up`, the second joining the first's router): `stack vehicles` lists
them with their state, a command reaches only the vehicle it names, and a vehicle that is not there, or a name
that cannot be one, is one clear error."""

import json
import re
import time

import pytest

from tests.support.harness import RunningStack, eventually, launch_profile, wait_no_processes


@pytest.fixture(scope="module")
def bus(tmp_path_factory):
    """Vehicles v1 and v2 on one bus, each `stack up` with its own STACK_HOME: (v1's stack, v2's, the endpoint)."""
    tmp = tmp_path_factory.mktemp("vehicles")
    first = RunningStack(tmp / "home1", launch_profile(tmp / "v1"), "--quiet", "--speed", "1")
    endpoint = first.wait_for(r"bus rendezvous (tcp/127\.0\.0\.1:\d+)").group(1)
    profile = launch_profile(tmp / "v2", extra=f'\n[bus]\nconnect = ["{endpoint}"]\n')
    profile.write_text(re.sub(r'(?m)^vehicle = "v1"', 'vehicle = "v2"', profile.read_text(), count=1))
    second = RunningStack(tmp / "home2", profile, "--quiet", "--speed", "1")
    try:
        first.wait_up()
        second.wait_up()
        yield first, second, endpoint
    finally:
        for stack in (second, first):
            assert stack.stop() == 0
            assert not wait_no_processes(stack.home)


def listed(stack: RunningStack, *args: str) -> dict[str, dict]:
    out = stack.cli("vehicles", "--json", *args)
    assert out.returncode == 0, out.stderr
    return {row["vehicle"]: row for row in json.loads(out.stdout)}


def test_vehicles_lists_every_vehicle_on_the_bus_with_its_state(bus):
    first, second, endpoint = bus
    eventually(
        lambda: all(r["modules_running"] == r["modules"] > 0 for r in listed(first).values()),
        what="every module of both vehicles running (the simulator waits for the lockstep's roster first)",
    )
    rows = listed(first)
    assert sorted(rows) == ["v1", "v2"]
    assert sorted(listed(second)) == ["v1", "v2"]  # from either stack's home
    assert sorted(listed(first, "--endpoint", endpoint)) == ["v1", "v2"]
    for row in rows.values():
        assert row["modules_not_running"] == {}
        assert row["lockstep"] is True
        assert row["armed"] is False
        assert "mode" in row and "position" in row and "battery" in row
    table = first.cli("vehicles").stdout.splitlines()
    assert table[0].split() == ["VEHICLE", "PROFILE", "MODE", "ARMED", "NORTH", "EAST", "ALT", "BATTERY", "MODULES"]
    assert [line.split()[0] for line in table[1:]] == ["v1", "v2"]


def test_a_vehicle_that_is_not_on_the_bus_is_one_clear_error(bus):
    first, _, endpoint = bus
    out = first.cli("topic", "list", "--endpoint", endpoint, "--vehicle", "v3")
    assert out.returncode == 1
    assert out.stderr.strip() == f"error: no vehicle 'v3' on the bus at {endpoint} (there: v1, v2)"
    out = first.cli("topic", "list", "--endpoint", endpoint)
    assert out.stderr.strip() == (
        f"error: several vehicles on the bus at {endpoint} (v1, v2): choose one with --vehicle"
    )
    out = first.cli("status", "--vehicle", "*")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: invalid vehicle name '*': use letters, digits, '_' and '-' only"
    out = first.cli("topic", "list", "--endpoint", endpoint, "--vehicle", "v2")
    assert out.returncode == 0 and "vehicle_status" in out.stdout


def test_status_all_gives_every_vehicle(bus):
    first, _, _ = bus
    out = first.cli("status", "--all", "--json")
    assert out.returncode == 0, out.stderr
    reports = json.loads(out.stdout)
    assert [r["vehicle"] for r in reports] == ["v1", "v2"]
    assert all("mode" in r["vehicle_summary"] and r["modules"] for r in reports)
    text = first.cli("status", "--all").stdout
    assert re.findall(r"(?m)^vehicle '(v\d)'", text) == ["v1", "v2"]
    out = first.cli("status", "--all", "--vehicle", "v1")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: --all addresses every vehicle: give it or --vehicle, not both"


def test_a_tool_on_the_other_stacks_router_gets_each_message_once(bus):
    first, _, endpoint = bus
    echo = ("topic", "echo", "vehicle_attitude", "-n", "50", "--json")
    out = first.cli(*echo, "--vehicle", "v2", "--endpoint", endpoint)
    assert out.returncode == 0, out.stderr
    stamps = [json.loads(line)["timestamp_sample"] for line in out.stdout.splitlines()]
    assert len(stamps) == 50 and stamps == sorted(set(stamps))


def arm(stack: RunningStack, *args: str) -> None:
    deadline = time.monotonic() + 120.0
    while True:  # until the estimates have converged the commander refuses to arm, for now
        out = stack.cli("cmd", "arm", *args)
        if out.returncode == 0 or time.monotonic() > deadline:
            break
        assert "TEMPORARILY_REJECTED" in out.stderr, out.stderr
        time.sleep(1.0)
    assert out.returncode == 0, out.stderr


def test_a_command_reaches_only_the_vehicle_it_names_or_all_of_them(bus):
    first, _, endpoint = bus
    arm(first, "--endpoint", endpoint, "--vehicle", "v2")
    try:
        rows = listed(first)
        assert rows["v2"]["armed"] is True
        assert rows["v1"]["armed"] is False
    finally:
        assert first.cli("cmd", "disarm", "--endpoint", endpoint, "--vehicle", "v2").returncode == 0
    assert listed(first)["v2"]["armed"] is False
    arm(first, "--all")
    try:
        assert [row["armed"] for row in listed(first).values()] == [True, True]
    finally:
        out = first.cli("cmd", "disarm", "--all")
    assert out.returncode == 0, out.stderr
    assert sorted(out.stdout.splitlines()) == ["v1: disarm: accepted", "v2: disarm: accepted"]
    assert [row["armed"] for row in listed(first).values()] == [False, False]
    out = first.cli("cmd", "hold", "--all", "--vehicle", "v1")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: --all addresses every vehicle: give it or --vehicle, not both; nothing sent"
