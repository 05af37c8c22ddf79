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
from stack.security.keystore import init_keystore, issue_identity
from tests.hosts.split import ROUTER_PORT, TAKEOFF_TIMEOUT_S, split_profile, take_off, up_on
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


RAW_DISARM = """
import sys, time
from stack.bus.node import Node
from stack.bus.config import BusConfig
from stack.msg.system import VehicleCommand
from stack.security.tls import tls_files
from pathlib import Path
bus = BusConfig(mode="client", connect=(sys.argv[1],), listen=(), tls=tls_files(Path(sys.argv[2]), "bob"))
with Node(bus, "v1", "not-a-tool") as node:
    pub = node.publisher("vehicle_command")
    for _ in range(20):
        pub.publish(VehicleCommand(command=400, param1=0.0, param2=21196.0, from_external=True, target_system=0,
                                   target_component=0))
        time.sleep(0.05)
"""
"""An observer's own program (not the CLI, which refuses) forcing a disarm (MAV_CMD_COMPONENT_ARM_DISARM, 21196):
the routers drop it."""

RAW_GARBAGE = """
import os, sys, time, zenoh
from pathlib import Path
from stack.bus.config import BusConfig
from stack.security.tls import tls_files
bus = BusConfig(mode="client", connect=(sys.argv[1],), listen=(), tls=tls_files(Path(sys.argv[2]), "alice"))
session = zenoh.open(bus.zenoh_config("garbage"))
for _ in range(20):
    for key in ("stack/v1/sensor_gyro/0", "stack/v1/vehicle_command/0"):
        session.put(key, os.urandom(64), attachment=os.urandom(40))
    time.sleep(0.05)
session.close()
"""
"""An operator's own program putting random bytes on a sensor topic (the router drops them: not a tool's to publish)
and on the command topic (let through to its subscribers, which drop them: no valid header)."""


FORGED_GYRO = """
import time
from stack.bus.node import Node
from stack.cli.common import find_stack
from stack.msg.sensors import SensorGyro
vehicle, bus = find_stack(None, None)
with Node(bus, vehicle, "simulator") as node:
    pub = node.publisher("sensor_gyro", announce=False)
    for _ in range(20):
        pub.publish(SensorGyro(x=3.0, y=3.0, z=3.0))
        time.sleep(0.05)
"""
"""A program on the flight-control host sending the simulator's topic under the simulator's publisher id, through its
own host's router (which lets its host's processes do anything) to the simulator's host."""


def keystore_for(net: Network, root: Path) -> Path:
    """A keystore with an identity for each host of the network (its address in it), an operator and an observer."""
    init_keystore(root)
    for host in net.hosts.values():
        if host.name != "visitor":
            issue_identity(root, host.name, "host", (host.address,))
    issue_identity(root, "alice", "operator")
    issue_identity(root, "bob", "observer")
    return root


def as_visitor(net: Network, keystore: Path, identity: str, *args: str) -> subprocess.CompletedProcess[str]:
    """A ``stack`` command from a machine that is not a host, as ``identity`` of ``keystore``, to the ground host."""
    visitor, ground = net.hosts["visitor"], net.hosts["ground"]
    env = {**stack_env(visitor.home), "STACK_KEYSTORE": str(keystore), "STACK_IDENTITY": identity}
    endpoint = f"tls/{ground.address}:{ROUTER_PORT}"
    return visitor.run(sys.executable, "-m", "stack", *args, "--endpoint", endpoint, env=env, timeout=120, cwd=REPO)


def own_program(net: Network, script: str, keystore: Path) -> subprocess.CompletedProcess[str]:
    """``script`` run on the visitor's machine, given the ground host's router and ``keystore``."""
    visitor, ground = net.hosts["visitor"], net.hosts["ground"]
    endpoint = f"tls/{ground.address}:{ROUTER_PORT}"
    return visitor.run(sys.executable, "-c", script, endpoint, str(keystore), env=stack_env(visitor.home), timeout=60,
                       cwd=REPO)  # fmt: skip


def visitors_see(net: Network, keystore: Path, work: Path) -> None:
    """From the visitor's machine, the hovering vehicle: read by an observer, never disarmed by one (through the CLI
    or a program of its own), closed to an identity of another keystore."""
    seen = as_visitor(net, keystore, "bob", "status", "--json")
    assert seen.returncode == 0, seen.stdout + seen.stderr
    assert json.loads(seen.stdout)["vehicle_summary"]["armed"]
    refused = as_visitor(net, keystore, "bob", "cmd", "disarm", "--force")
    assert refused.returncode == 2, refused.stdout + refused.stderr
    assert "identity bob is an observer: it may read the vehicle, not command it; nothing sent" in refused.stderr
    visitor, ground = net.hosts["visitor"], net.hosts["ground"]
    forced = own_program(net, RAW_DISARM, keystore)
    assert forced.returncode == 0, forced.stdout + forced.stderr
    after = status(ground)
    assert after is not None and after["vehicle_summary"]["armed"], "an observer's disarm reached the vehicle"
    assert after["vehicle_summary"]["position"]["altitude_above_home"] > 2.0
    # dropped without a word to bob's program, counted by the ground host's router that dropped it
    bobs = [
        (d["action"], d["flow"], d["key"], d["count"]) for d in after["denied"].get("ground", []) if d["who"] == "bob"
    ]
    assert [b[:3] for b in bobs] == [("put", "ingress", "stack/v1/vehicle_command/0")] and bobs[0][3] >= 1, bobs
    garbage = own_program(net, RAW_GARBAGE, keystore)
    assert garbage.returncode == 0, garbage.stdout + garbage.stderr
    after = status(ground)
    assert after is not None and after["vehicle_summary"]["armed"], "garbage disarmed the vehicle"
    assert after["vehicle_summary"]["position"]["altitude_above_home"] > 2.0
    alices = {(d["action"], d["key"]) for d in after["denied"].get("ground", []) if d["who"] == "alice"}
    assert alices == {("put", "stack/v1/sensor_gyro/0")}, after["denied"]
    commander = next(m for m in after["modules"] if m["module"] == "commander")
    dropped = ("decode_errors", "schema_errors", "foreign", "unauthorized", "invalid")
    assert sum(commander.get(k, 0) for k in dropped) >= 1, commander
    stranger = work / "other-keys"
    init_keystore(stranger)
    issue_identity(stranger, "mallory", "operator")
    env = {**stack_env(visitor.home), "STACK_KEYSTORE": str(stranger), "STACK_IDENTITY": "mallory"}
    out = visitor.run(
        sys.executable, "-m", "stack", "cmd", "disarm", "--force", "--endpoint", f"tls/{ground.address}:{ROUTER_PORT}",
        env=env, timeout=120, cwd=REPO,
    )  # fmt: skip
    assert out.returncode == 1 and "did not admit identity mallory" in out.stderr, out.stdout + out.stderr


def hosts_keep_to_their_topics(net: Network) -> None:
    """The flight-control host's certificate does not carry another host's module's topic: the simulator's host drops
    the forged gyro, counted under the control host's name, and the vehicle hovers on."""
    control, ground = net.hosts["control"], net.hosts["ground"]
    forged = control.run(sys.executable, "-c", FORGED_GYRO, env=stack_env(control.home), timeout=60, cwd=REPO)
    assert forged.returncode == 0, forged.stdout + forged.stderr

    def denied_on_sim() -> set[tuple[str, str, str]]:
        report = status(ground)
        return {(d["who"], d["action"], d["key"]) for d in (report or {}).get("denied", {}).get("sim", [])}

    eventually(lambda: ("control", "put", "stack/v1/sensor_gyro/0") in denied_on_sim(), 30.0, "the forgery counted")
    after = status(ground)
    assert after is not None and after["vehicle_summary"]["armed"]
    assert after["vehicle_summary"]["position"]["altitude_above_home"] > 2.0


@pytest.mark.parametrize("realtime", [False, True], ids=["lockstep, mutual TLS", "realtime"])
def test_takeoff_hover_and_land_across_three_hosts_commanded_from_the_ground(network, tmp_path, realtime):
    """In lockstep the ground host also records the whole vehicle (in real time, three hosts' stacks and a recorder
    of every topic are more than the two cores of the test machine run on the wall clock). In real time the
    flight-control host's monotonic clock is 100 s ahead of the others', as another machine's would be: its
    modules run on the vehicle's time base (stack.bus.timebase), else they would judge every sample of the
    simulator's host 100 s old. In lockstep the links between hosts are mutual TLS from a keystore, with its
    access rules: from a visitor's machine, an observer reads but its disarm never reaches the vehicle, an identity
    of another keystore is not admitted, and an operator lands the vehicle; a host publishes only its modules'
    topics."""
    ahead = {"control": 100} if realtime else None
    # a laptop the profile gives no module (its router, tools), and a visitor's machine that is no host at all
    net = network((*HOSTS, "laptop", "visitor"), clock_ahead_s=ahead)
    keystore = None if realtime else keystore_for(net, tmp_path / "keys")
    secure = "" if keystore is None else f'[security]\nkeystore = "{keystore}"\n'
    hosts = [h for name, h in net.hosts.items() if name != "visitor"]
    profile = split_profile(tmp_path / "split.toml", net, secure, hosts)
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
    if keystore is None:
        land = stack(ground, "cmd", "land", "--wait")
    else:
        visitors_see(net, keystore, tmp_path)
        hosts_keep_to_their_topics(net)
        land = as_visitor(net, keystore, "alice", "cmd", "land", "--wait")  # an operator from afar
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
