"""`stack up --vehicles 2`: two copies of the default profile's vehicle on one bus, the second joining the first's
router.

`stack vehicles` lists them with their state; `--all` and `--vehicle` address all of them or one, and a vehicle that
is not there, or a name that cannot be one, is one clear error; `stack plot --all` draws both in one view. Each is
its own MAVLink system with PX4 multi-vehicle SITL's numbering: every ground-station link sends to the one ground-
station port, where MAVSDK finds systems 1 and 2; vehicle i's API link sends i - 1 ports further, where MAVSDK finds
system i alone. Both keep one simulated clock: a vehicle whose simulator stands still holds the other. The links'
first ports are free ones (the launch profile's are PX4's fixed ones); the swarm runs at real speed, which is all
these checks need.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest
from mavsdk.asyncio import ComponentType, Configuration, Mavsdk

from stack.mathlib.geo import MapProjection
from tests.mavlink.peer import Link, links_profile, udp_port
from tests.support.harness import RunningStack, eventually, wait_no_processes
from tests.viz.rrd import read_rrd

VEHICLES = ("v1", "v2")


@dataclass
class Swarm:
    running: RunningStack
    endpoint: str
    """The first vehicle's router, which the second joined."""
    gcs: Link
    api: Link

    def cli(self, *args: str):
        return self.running.cli(*args)

    def listed(self, *args: str) -> dict[str, dict]:
        out = self.cli("vehicles", "--json", *args)
        assert out.returncode == 0, out.stderr
        return {row["vehicle"]: row for row in json.loads(out.stdout)}


@pytest.fixture(scope="module")
def swarm(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Swarm]:
    home = tmp_path_factory.mktemp("swarm")
    gcs = Link("mavlink_gcs", udp_port(), udp_port(), extra=", shared_remote = true")
    api = Link("mavlink_api", udp_port(), udp_port())
    profile = links_profile(home / "swarm.toml", [gcs, api])
    running = RunningStack(home, profile, "--vehicles", str(len(VEHICLES)), "--quiet", "--speed", "1")
    try:
        endpoint = running.wait_for(r"^v1: \[stack\] bus rendezvous (tcp/127\.0\.0\.1:\d+)").group(1)
        for vehicle in VEHICLES:
            running.wait_for(rf"^{vehicle}: \[stack\] all \d+ modules up", 120)
        yield Swarm(running, endpoint, gcs, api)
    finally:
        code = running.stop()
    assert code == 0, running.output
    assert "Traceback" not in running.output
    assert not wait_no_processes(home)


def test_every_vehicle_is_on_the_bus_with_its_state_system_id_and_home(swarm):
    eventually(
        lambda: [(r["modules_running"] == r["modules"] > 0) for r in swarm.listed().values()] == [True, True],
        what="every module of both vehicles running (the simulator waits for the lockstep's roster first)",
    )
    rows = swarm.listed()
    assert sorted(swarm.listed("--endpoint", swarm.endpoint)) == list(VEHICLES)
    for row in rows.values():
        assert row["modules_not_running"] == {} and row["lockstep"] is True and row["armed"] is False
        assert "mode" in row and "position" in row and "battery" in row
    table = swarm.cli("vehicles").stdout.splitlines()
    assert table[0].split() == ["VEHICLE", "PROFILE", "MODE", "ARMED", "NORTH", "EAST", "ALT", "BATTERY", "MODULES"]
    assert [line.split()[0] for line in table[1:]] == list(VEHICLES)
    fixes = {}
    for i, vehicle in enumerate(VEHICLES, start=1):
        out = swarm.cli("param", "get", "MAV_SYS_ID", "--vehicle", vehicle)
        assert out.returncode == 0 and out.stdout.startswith(f"MAV_SYS_ID = {i} "), out.stdout + out.stderr
        out = swarm.cli("topic", "echo", "sensor_gps", "-n", "1", "--json", "--vehicle", vehicle)
        assert out.returncode == 0, out.stderr
        fixes[vehicle] = json.loads(out.stdout)
    origin = MapProjection(fixes["v1"]["latitude_deg"], fixes["v1"]["longitude_deg"])
    for i, vehicle in enumerate(VEHICLES):
        north, east = origin.project(fixes[vehicle]["latitude_deg"], fixes[vehicle]["longitude_deg"])
        assert abs(north) < 2.0 and abs(east - 5.0 * i) < 2.0, (vehicle, north, east)


def test_status_all_gives_every_vehicle(swarm):
    out = swarm.cli("status", "--all", "--json")
    assert out.returncode == 0, out.stderr
    reports = json.loads(out.stdout)
    assert [r["vehicle"] for r in reports] == list(VEHICLES)
    assert all("mode" in r["vehicle_summary"] and r["modules"] for r in reports)
    assert re.findall(r"(?m)^vehicle '(v\d)'", swarm.cli("status", "--all").stdout) == list(VEHICLES)
    out = swarm.cli("status", "--all", "--vehicle", "v1")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: --all addresses every vehicle: give it or --vehicle, not both"


def test_a_vehicle_that_is_not_on_the_bus_is_one_clear_error(swarm):
    endpoint = swarm.endpoint
    out = swarm.cli("topic", "list", "--endpoint", endpoint, "--vehicle", "v3")
    assert out.returncode == 1
    assert out.stderr.strip() == f"error: no vehicle 'v3' on the bus at {endpoint} (there: v1, v2)"
    out = swarm.cli("topic", "list", "--endpoint", endpoint)
    assert out.stderr.strip() == f"error: several vehicles on the bus at {endpoint} (v1, v2): choose one with --vehicle"
    out = swarm.cli("status", "--vehicle", "*")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: invalid vehicle name '*': use letters, digits, '_' and '-' only"
    out = swarm.cli("topic", "list", "--endpoint", endpoint, "--vehicle", "v2")
    assert out.returncode == 0 and "vehicle_status" in out.stdout


def test_a_tool_on_the_other_vehicles_router_gets_each_message_once(swarm):
    echo = ("topic", "echo", "vehicle_attitude", "-n", "50", "--json")
    out = swarm.cli(*echo, "--vehicle", "v2", "--endpoint", swarm.endpoint)
    assert out.returncode == 0, out.stderr
    stamps = [json.loads(line)["timestamp_sample"] for line in out.stdout.splitlines()]
    assert len(stamps) == 50 and stamps == sorted(set(stamps))


def arm(swarm: Swarm, *args: str) -> None:
    deadline = time.monotonic() + 120.0
    while True:  # until the estimates have converged the commander refuses to arm, for now
        out = swarm.cli("cmd", "arm", *args)
        if out.returncode == 0 or time.monotonic() > deadline:
            break
        assert "TEMPORARILY_REJECTED" in out.stderr, out.stderr
        time.sleep(1.0)
    assert out.returncode == 0, out.stderr


def test_a_command_reaches_only_the_vehicle_it_names_or_all_of_them(swarm):
    arm(swarm, "--endpoint", swarm.endpoint, "--vehicle", "v2")
    try:
        rows = swarm.listed()
        assert (rows["v1"]["armed"], rows["v2"]["armed"]) == (False, True)
    finally:
        assert swarm.cli("cmd", "disarm", "--endpoint", swarm.endpoint, "--vehicle", "v2").returncode == 0
    assert swarm.listed()["v2"]["armed"] is False
    arm(swarm, "--all")
    try:
        assert [row["armed"] for row in swarm.listed().values()] == [True, True]
    finally:
        out = swarm.cli("cmd", "disarm", "--all")
    assert out.returncode == 0, out.stderr
    assert sorted(out.stdout.splitlines()) == ["v1: disarm: accepted", "v2: disarm: accepted"]
    assert [row["armed"] for row in swarm.listed().values()] == [False, False]
    out = swarm.cli("cmd", "hold", "--all", "--vehicle", "v1")
    assert out.returncode == 2
    assert out.stderr.strip() == "error: --all addresses every vehicle: give it or --vehicle, not both; nothing sent"


def test_plot_all_draws_every_vehicle_in_one_view(swarm, tmp_path):
    rrd = tmp_path / "swarm.rrd"
    out = swarm.cli("plot", "--all", "--save", str(rrd), "--duration", "3")
    assert out.returncode == 0, out.stderr
    assert "plotting v1" in out.stdout and "plotting v2" in out.stdout
    content = read_rrd(rrd)
    where = {}
    for vehicle in VEHICLES:
        for root in ("/swarm/world", "/swarm/height", "/swarm/speed", "/swarm/battery"):
            assert content.rows(f"{root}/{vehicle}") > 0, (root, vehicle, sorted(content.entities()))
        where[vehicle] = content.values(f"/swarm/world/{vehicle}", "Points3D:positions")[-1][0]
    north, east, _ = (where["v2"][i] - where["v1"][i] for i in range(3))
    assert abs(north) < 2.0 and abs(east - 5.0) < 2.0, where  # drawn as far apart as their homes are
    events = [row[0] for row in content.values("/swarm/events", "TextLog:text")]
    assert any(e.startswith("v1: ") for e in events) and any(e.startswith("v2: ") for e in events), events


async def systems_heard(port: int, count: int) -> set[int]:
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        await mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
        for _ in range(100):
            if len(await mavsdk.get_systems()) >= count:
                break
            await asyncio.sleep(0.1)
        await asyncio.sleep(1.0)  # a system more than expected would show by now
        return {await system.get_system_id() for system in await mavsdk.get_systems()}
    finally:
        mavsdk.destroy()


def test_mavsdk_finds_every_vehicle_on_the_ground_station_port_and_each_on_its_api_port(swarm):
    assert asyncio.run(systems_heard(swarm.gcs.remote, len(VEHICLES))) == {1, 2}
    for i in range(len(VEHICLES)):
        assert asyncio.run(systems_heard(swarm.api.remote + i, 1)) == {i + 1}


def sim_time_us(swarm: Swarm, vehicle: str) -> int:
    """The vehicle's simulated time as its modules' latest heartbeats (about 1 Hz of wall time) give it."""
    status = json.loads(swarm.cli("status", "--json", "--vehicle", vehicle).stdout)
    return max(m.get("sim_time_us", 0) for m in status["modules"])


def test_one_world_clock_holds_every_vehicle_to_the_slowest(swarm):
    status = json.loads(swarm.cli("status", "--json", "--vehicle", "v2").stdout)
    simulator = next(m["pid"] for m in status["modules"] if m["module"] == "simulator")
    os.kill(simulator, signal.SIGSTOP)
    try:
        time.sleep(1.5)  # every heartbeat read from now on was sent while v2's clock stood still
        before = sim_time_us(swarm, "v1")
        time.sleep(1.5)
        after = sim_time_us(swarm, "v1")
    finally:
        os.kill(simulator, signal.SIGCONT)
    assert after - before <= 4000, f"v1 went on {after - before} µs while v2 stood still"
    eventually(lambda: sim_time_us(swarm, "v1") > after + 1_000_000, what="v1's time going on with v2's")
