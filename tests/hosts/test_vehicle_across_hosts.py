"""One vehicle over three hosts (network namespaces joined by a bridge): the simulator and the estimators, the flight
control, and a ground host with the MAVLink links. Each host runs ``stack up PROFILE --host NAME`` with a STACK_HOME
of its own, as separate machines would; the lockstep spans them (its shared memory on the simulator's host, the
others over Zenoh), and the ground host commands and watches the whole vehicle."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from stack.bus.node import stable_publisher_id
from stack.record.recorder import RecordedMessage, RecordingReader
from tests.hosts.split import TAKEOFF_TIMEOUT_S, split_profile, take_off, up_on
from tests.hosts.split import stack_on as stack
from tests.support.harness import REPO, eventually, stack_env
from tests.support.hosts import Host, Network

# Three hosts' stacks at once (at real-time priority, in real time): never beside the simulated Pixhawk's real-time
# flights (tests/flight/test_pixhawk_flight.py), which they would starve.
pytestmark = [pytest.mark.timeout(400), pytest.mark.xdist_group("heavy_wall_clock")]

HOSTS = ("sim", "control", "ground")
START_TIMEOUT_S = 240.0  # three stacks starting on a loaded two-core machine


def status(host: Host) -> dict | None:
    out = stack(host, "status", "--json", timeout=60.0)
    return json.loads(out.stdout) if out.returncode == 0 else None


def bring_up(
    net: Network, names: list[str], profile: Path, tmp_path: Path, *args: str, record: Path | None = None
) -> dict[str, subprocess.Popen[str]]:
    """The share of each host named, the ground host recording the whole vehicle to ``record``."""
    procs = {}
    for name in names:
        recording = ("--record", str(record)) if name == "ground" and record is not None else ()
        procs[name] = up_on(net.hosts[name], profile, tmp_path / f"{name}.log", *args, *recording)
    return procs


def assert_each_message_once(messages: list[RecordedMessage]) -> None:
    """Every publisher numbers its messages per topic: none missing after the first heard, none twice."""
    channels: dict[tuple[str, int, int], list[int]] = {}
    for m in messages:
        channels.setdefault((m.topic, m.instance, m.publisher_id), []).append(m.index)
    for channel, indices in channels.items():
        assert indices == list(range(indices[0], indices[0] + len(indices))), channel


def running(report: dict | None, count: int) -> bool:
    """The ``count`` modules of the vehicle running, and its clock going (simulated time, in lockstep)."""
    if report is None or len(report["modules"]) != count:
        return False
    modules = report["modules"]
    clock = not report["lockstep"] or any(m.get("sim_time_us") for m in modules)
    return all(m["state"] == "running" for m in modules) and clock


@pytest.mark.parametrize("realtime", [False, True], ids=["lockstep", "realtime"])
def test_takeoff_hover_and_land_across_three_hosts_commanded_from_the_ground(network, tmp_path, realtime):
    """In lockstep the ground host also records the whole vehicle (in real time, three hosts' stacks and a recorder
    of every topic are more than the two cores of the test machine run on the wall clock). In real time the
    flight-control host's monotonic clock is 100 s ahead of the others', as another machine's would be: its
    modules run on the vehicle's time base (stack.bus.timebase), else they would judge every sample of the
    simulator's host 100 s old."""
    ahead = {"control": 100} if realtime else None
    net = network((*HOSTS, "laptop"), clock_ahead_s=ahead)  # a laptop the profile gives no module: its router, tools
    profile = split_profile(tmp_path / "split.toml", net)
    laptop = net.hosts["laptop"]
    router = laptop.popen(
        sys.executable, "-m", "stack", "router", str(profile), "--host", "laptop", "--insecure",
        env=stack_env(laptop.home), stdout=(tmp_path / "laptop.log").open("w"), stderr=subprocess.STDOUT, cwd=REPO,
    )  # fmt: skip
    recording = None if realtime else tmp_path / "ground.mcap"
    mode = ["--realtime"] if realtime else []
    procs = bring_up(net, ["sim", "ground"], profile, tmp_path, *mode, record=recording)
    ground = net.hosts["ground"]
    logs = lambda: "\n".join((tmp_path / f"{h}.log").read_text() for h in procs)  # noqa: E731
    # the flight-control host not started yet: the others wait for it, and say whose modules are missing
    silent = "host control: its supervisor does not answer (lost, or not started): commander, control_allocator"
    eventually(lambda: silent in stack(ground, "status").stdout, START_TIMEOUT_S, "the missing host named")
    procs.update(bring_up(net, ["control"], profile, tmp_path, *mode))
    count = 12 if recording is None else 13  # the profile's modules, and the ground host's recorder
    eventually(lambda: running(status(ground), count), START_TIMEOUT_S, "the vehicle up on all hosts")

    report = status(ground)
    assert report is not None and report["hosts"] == list(HOSTS)
    placed = {m["module"]: m["host"] for m in report["modules"]}
    assert placed["simulator"] == placed["local_position_estimator"] == "sim"
    assert placed["commander"] == placed["mc_pos_control"] == "control"
    assert placed["mavlink_gcs"] == "ground"

    eventually(lambda: take_off(ground, 3), TAKEOFF_TIMEOUT_S, "a takeoff accepted and complete")
    hover = status(laptop)  # any host sees the whole vehicle, a host with only a router too
    assert hover is not None and hover["vehicle_summary"]["armed"]
    assert hover["vehicle_summary"]["position"]["altitude_above_home"] > 2.0
    # the tools of the ground host reach modules of the other hosts
    param = stack(ground, "param", "set", "MPC_XY_VEL_MAX", "11.5")  # mc_pos_control's, on the control host
    assert param.returncode == 0, param.stdout + param.stderr
    assert "11.5" in stack(net.hosts["sim"], "param", "get", "MPC_XY_VEL_MAX").stdout
    echo = stack(ground, "topic", "echo", "vehicle_attitude", "--count", "3", "--json")  # from the sim host's fast path
    assert echo.returncode == 0 and len(echo.stdout.splitlines()) == 3, echo.stdout + echo.stderr
    land = stack(ground, "cmd", "land", "--wait")
    assert land.returncode == 0 and "landed and disarmed" in land.stdout, land.stdout + land.stderr + logs()

    down = stack(ground, "down")  # from any host, the whole vehicle
    assert down.returncode == 0, down.stdout + down.stderr
    assert "stopping host sim" in down.stdout and "stopping host control" in down.stdout
    codes = {name: p.wait(timeout=60) for name, p in procs.items()}
    assert codes == dict.fromkeys(HOSTS, 0), f"{codes}\n{logs()}"
    assert "Traceback" not in logs()
    if realtime:
        offset = re.search(r"clock: on host sim's, ([-+]\d+\.\d+) s", (tmp_path / "control.log").read_text())
        assert offset is not None and abs(float(offset.group(1)) + 100.0) < 0.01
    assert stack(laptop, "down").returncode == 0 and router.wait(timeout=60) == 0
    if recording is None:
        return
    with RecordingReader(recording) as reader:
        messages = list(reader.iter_messages())
    publishers = {stable_publisher_id("v1", name): host for name, host in placed.items()}
    heard_from = {publishers[m.publisher_id] for m in messages if m.publisher_id in publishers}
    assert heard_from == {"sim", "control"}  # the ground host's links publish on the wall clock only when used
    assert_each_message_once(messages)

