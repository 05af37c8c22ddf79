"""`stack up --vehicles 3`: three copies of the default profile's vehicle on one bus, each its own MAVLink system
with PX4 multi-vehicle SITL's numbering: every ground-station link sends to the one ground-station port, where
MAVSDK finds systems 1, 2 and 3; vehicle i's API link sends i - 1 ports further, where MAVSDK finds system i alone.
The links' first ports are free ones (the launch profile's are PX4's fixed ones)."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Iterator

import pytest
from mavsdk.asyncio import ComponentType, Configuration, Mavsdk

from stack.mathlib.geo import MapProjection
from tests.mavlink.peer import Link, links_profile, udp_port
from tests.support.harness import RunningStack, eventually, wait_no_processes

VEHICLES = ("v1", "v2", "v3")


@pytest.fixture(scope="module")
def swarm(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[RunningStack, Link, Link]]:
    home = tmp_path_factory.mktemp("swarm")
    gcs = Link("mavlink_gcs", udp_port(), udp_port(), extra=", shared_remote = true")
    api = Link("mavlink_api", udp_port(), udp_port())
    running = RunningStack(home, links_profile(home / "swarm.toml", [gcs, api]), "--vehicles", "3", "--quiet")
    try:
        for vehicle in VEHICLES:
            running.wait_for(rf"^{vehicle}: \[stack\] all \d+ modules up", 120)
        yield running, gcs, api
    finally:
        code = running.stop()
    assert code == 0, running.output
    assert "Traceback" not in running.output
    assert not wait_no_processes(home)


def test_every_vehicle_is_on_the_bus_with_its_own_system_id_and_home(swarm):
    running, _, _ = swarm

    def listed() -> dict[str, dict]:
        return {r["vehicle"]: r for r in json.loads(running.cli("vehicles", "--json").stdout)}

    eventually(lambda: all(r["modules_running"] == r["modules"] for r in listed().values()) and len(listed()) == 3)
    assert sorted(listed()) == list(VEHICLES)
    homes = {}
    for i, vehicle in enumerate(VEHICLES, start=1):
        out = running.cli("param", "get", "MAV_SYS_ID", "--vehicle", vehicle)
        assert out.returncode == 0 and out.stdout.startswith(f"MAV_SYS_ID = {i} "), out.stdout + out.stderr
        out = running.cli("topic", "echo", "sensor_gps", "-n", "1", "--json", "--vehicle", vehicle)
        assert out.returncode == 0, out.stderr
        homes[vehicle] = json.loads(out.stdout)
    origin = MapProjection(homes["v1"]["latitude_deg"], homes["v1"]["longitude_deg"])
    for i, vehicle in enumerate(VEHICLES):
        north, east = origin.project(homes[vehicle]["latitude_deg"], homes[vehicle]["longitude_deg"])
        assert abs(north) < 2.0 and abs(east - 5.0 * i) < 2.0, (vehicle, north, east)


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
    _, gcs, api = swarm
    assert asyncio.run(systems_heard(gcs.remote, 3)) == {1, 2, 3}
    for i in range(3):
        assert asyncio.run(systems_heard(api.remote + i, 1)) == {i + 1}
