"""A Pixhawk on a companion computer, and a ground laptop (launch/pixhawk_hosts.toml), as two hosts of a test
network: the companion runs the flight stack beside the Pixhawk (here ``stack pixhawk-sim``, on the companion's
loopback where a real one is on its serial port); the laptop runs the ground-station link, which a ground station
on the laptop reaches on its own loopback, and commands the vehicle."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from tests.hosts.split import ROUTER_PORT, TAKEOFF_TIMEOUT_S, take_off, up_on
from tests.hosts.split import stack_on as stack
from tests.hosts.test_vehicle_across_hosts import START_TIMEOUT_S, running, status
from tests.support.harness import REPO, eventually, stack_env, write_profile
from tests.support.hosts import Host

pytestmark = [pytest.mark.timeout(400), pytest.mark.xdist_group("heavy_wall_clock")]

PIXHAWK_LINK_PORT = 14540  # PX4 SITL's offboard port, inside the companion's own namespace
# The simulated Pixhawk's vehicle (its hover thrust, for the position loop) and its magnetic declination.
VEHICLE = '[stack]\nairframe = "sih_quad"\n\n[params]\nATT_MAG_DECL = 3.2\n'


def ground_station_hears(ground: Host, armed: bool, heard: list[dict]) -> bool:
    """Whether a ground station on the laptop's UDP 14550 hears the vehicle ``armed`` or not for 2 s (``stack
    mavlink inspect``); what it heard is appended to ``heard``."""
    out = stack(ground, "mavlink", "inspect", "udp:127.0.0.1:14550", "--seconds", "2", "--json")
    assert out.returncode == 0, out.stdout + out.stderr
    heard.append(json.loads(out.stdout))
    return heard[-1]["armed"] == armed


def test_a_pixhawk_on_the_companion_flown_from_the_ground_laptop(network, tmp_path: Path) -> None:
    net = network(("companion", "ground"))
    companion, ground = net.hosts["companion"], net.hosts["ground"]
    endpoints = "".join(f'[hosts.{h.name}]\nendpoint = "tcp/{h.address}:{ROUTER_PORT}"\n\n' for h in net.hosts.values())
    profile = write_profile(tmp_path / "pixhawk.toml", f'extends = "pixhawk_hosts"\n\n{endpoints}{VEHICLE}')
    companion.popen(
        sys.executable, "-m", "stack", "pixhawk-sim", "--seed", "1", "--link", f"udpout:127.0.0.1:{PIXHAWK_LINK_PORT}",
        env=stack_env(companion.home), stdout=(tmp_path / "pixhawk.log").open("w"), cwd=REPO,
    )  # fmt: skip
    device = ("--device", f"udpin:127.0.0.1:{PIXHAWK_LINK_PORT}")
    procs = {
        "companion": up_on(companion, profile, tmp_path / "companion.log", *device),
        "ground": up_on(ground, profile, tmp_path / "ground.log"),
    }
    logs = lambda: "\n".join(p.read_text() for p in tmp_path.glob("*.log"))  # noqa: E731
    eventually(lambda: running(status(ground), 9), START_TIMEOUT_S, "the vehicle up on both hosts")
    placed = {m["module"]: m["host"] for m in (status(ground) or {})["modules"]}
    assert placed["pixhawk"] == placed["commander"] == "companion" and placed["mavlink_gcs"] == "ground"
    heard: list[dict] = []
    eventually(lambda: ground_station_hears(ground, False, heard), 30.0, "the ground station hearing the vehicle")
    assert (heard[-1]["system_id"], heard[-1]["autopilot"]) == (1, "PX4"), heard[-1]

    eventually(lambda: take_off(ground, 3), TAKEOFF_TIMEOUT_S, "a takeoff from the laptop")
    eventually(lambda: ground_station_hears(ground, True, heard), 30.0, "the ground station hearing it armed")
    names = {m["name"] for m in heard[-1]["messages"]}
    assert {"GLOBAL_POSITION_INT", "ATTITUDE", "SYS_STATUS"} <= names, names
    hover = status(ground)
    assert hover is not None and hover["vehicle_summary"]["position"]["altitude_above_home"] > 2.0, hover
    land = stack(ground, "cmd", "land", "--wait")
    assert land.returncode == 0 and "landed and disarmed" in land.stdout, land.stdout + land.stderr + logs()

    assert stack(ground, "down").returncode == 0
    codes = {name: p.wait(timeout=60) for name, p in procs.items()}
    assert codes == {"companion": 0, "ground": 0}, f"{codes}\n{logs()}"
    assert "Traceback" not in logs()
