"""The access rules a keystore gives a host's router (stack.security.acl), on real routers over loopback: the host's
own processes do everything; another host publishes its own modules' topics, not another's; an operator commands
and reads; an observer only reads; a command the router would drop is refused at the tool, saying why."""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig, open_router
from stack.bus.ports import free_port
from stack.security.keystore import init_keystore, issue_identity
from stack.security.tls import tls_files
from stack.supervisor.profile import load_profile
from tests.security.test_host_links import hosts_profile
from tests.support.harness import REPO, stack_env

ATTITUDE, COMMAND, GYRO = "stack/v1/vehicle_attitude/0", "stack/v1/vehicle_command/0", "stack/v1/sensor_gyro/0"
STATUS = "stack/v1/vehicle_status/0"


class Heard:
    def __init__(self, session: zenoh.Session, key: str) -> None:
        self.samples: list[str] = []
        self.arrived = threading.Event()
        self.sub = session.declare_subscriber(key, self._on)

    def _on(self, sample: zenoh.Sample) -> None:
        self.samples.append(sample.payload.to_string())
        self.arrived.set()


def client(endpoint: str, tls: dict[str, str] | None = None) -> zenoh.Session:
    return zenoh.open(BusConfig(mode="client", connect=(endpoint,), listen=(), tls=tls or {}).zenoh_config("client"))


def roles_keystore(root: Path) -> Path:
    """A keystore with the three hosts of the profile, an operator (alice) and an observer (bob)."""
    init_keystore(root)
    for name, role in (("sim", "host"), ("control", "host"), ("ground", "host"), ("alice", "operator"),
                       ("bob", "observer")):  # fmt: skip
        issue_identity(root, name, role)
    return root


def test_each_role_gets_what_it_may_and_nothing_more(tmp_path: Path) -> None:
    keystore = roles_keystore(tmp_path / "keys")
    ports = {h: free_port() for h in ("sim", "control", "ground")}
    profile = load_profile(str(hosts_profile(tmp_path, keystore, ports)))
    local = f"tcp/127.0.0.1:{free_port()}"
    listen = profile.router_links("sim")[0]
    sim_bus = BusConfig(
        mode="router", listen=(local, *listen), tls=profile.host_tls("sim"), access=profile.host_access()
    )
    sim = open_router(sim_bus, "router-sim", 2)
    tls_endpoint = listen[0].partition("#")[0]
    sessions = []
    try:
        module = client(local)  # a module of the simulator's host
        alice = client(tls_endpoint, tls_files(keystore, "alice"))
        bob = client(tls_endpoint, tls_files(keystore, "bob"))
        control = client(tls_endpoint, tls_files(keystore, "control"))  # the flight-control host
        sessions += [module, alice, bob, control]
        commands, gyro, states = Heard(module, COMMAND), Heard(module, GYRO), Heard(module, STATUS)
        telemetry = {"alice": Heard(alice, ATTITUDE), "bob": Heard(bob, ATTITUDE)}
        deadline = time.monotonic() + 10
        while not all(h.arrived.is_set() for h in telemetry.values()) and time.monotonic() < deadline:
            module.put(ATTITUDE, "attitude")  # every identity that may read hears the vehicle
            time.sleep(0.1)
        assert all(h.samples and h.samples[0] == "attitude" for h in telemetry.values())
        for _ in range(5):
            bob.put(COMMAND, "bob")  # an observer's command: dropped
            alice.put(GYRO, "alice")  # an operator may command, not fake the sensors
            alice.put(COMMAND, "alice")
            control.put(STATUS, "control")  # its commander's
            control.put(GYRO, "control")  # the simulator's, on the simulator's host
            time.sleep(0.1)
        assert commands.arrived.wait(5.0) and states.arrived.wait(5.0)
        time.sleep(0.3)
        assert set(commands.samples) == {"alice"} and set(states.samples) == {"control"} and gyro.samples == []
        out = subprocess.run(
            [sys.executable, "-m", "stack", "cmd", "disarm", "--force", "--endpoint", tls_endpoint],
            env={**stack_env(tmp_path), "STACK_KEYSTORE": str(keystore), "STACK_IDENTITY": "bob"},
            capture_output=True, text=True, timeout=60, cwd=REPO,
        )  # fmt: skip
        assert out.returncode == 2
        assert out.stderr.strip() == (
            "error: identity bob is an observer: it may read the vehicle, not command it; nothing sent"
        )
    finally:
        for s in sessions:
            s.close()
        sim.close()


def test_the_access_rules_name_every_area_of_the_runtimes_keys() -> None:
    """A key area the rules do not name is denied to everyone, the host's own modules too (no wildcard covers it)."""
    used = set()
    for path in (REPO / "stack").rglob("*.py"):
        used |= set(re.findall(r"/@([a-z_]+)/", path.read_text()))
    assert used <= set(keys.AREAS), used - set(keys.AREAS)


def test_a_router_counts_what_its_access_rules_deny_and_names_who_tried(tmp_path: Path) -> None:
    """Zenoh drops a denied message without a word to its sender; the router's process counts each (from Zenoh's
    own log, stack.security.denials) and says who tried what, once per kind, and how many at the end."""
    keystore = roles_keystore(tmp_path / "keys")
    ports = {h: free_port() for h in ("sim", "control", "ground")}
    path = hosts_profile(tmp_path, keystore, ports)
    router = subprocess.Popen(
        [sys.executable, "-m", "stack", "router", str(path), "--host", "sim"],
        env=stack_env(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=REPO,
    )  # fmt: skip
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(iter(router.stdout.readline, "")), daemon=True)
    reader.start()
    sessions = []
    try:
        deadline = time.monotonic() + 60
        while not any("router of host sim, vehicle" in line for line in lines) and time.monotonic() < deadline:
            assert router.poll() is None, lines
            time.sleep(0.05)
        local, tls_endpoint = re.search(r": on (tcp/\S+), (tls/[^#,;\s]+)", "".join(lines)).groups()
        module = client(local)
        alice = client(tls_endpoint, tls_files(keystore, "alice"))
        bob = client(tls_endpoint, tls_files(keystore, "bob"))
        sessions += [module, alice, bob]
        heard = Heard(bob, ATTITUDE)
        while not heard.arrived.is_set() and time.monotonic() < deadline:
            module.put(ATTITUDE, "attitude")
            time.sleep(0.1)
        assert heard.arrived.is_set()
        for _ in range(3):
            bob.put(COMMAND, "bob")
            alice.put(GYRO, "alice")
        wanted = {"denied bob a put (ingress) on stack/v1/vehicle_command/0",
                  "denied alice a put (ingress) on stack/v1/sensor_gyro/0"}  # fmt: skip
        while not all(any(w in line for line in lines) for w in wanted) and time.monotonic() < deadline:
            time.sleep(0.05)
        said = [line for line in lines if "denied" in line]
        assert all(sum(w in line for line in said) == 1 for w in wanted), said  # once per kind
    finally:
        for s in sessions:
            s.close()
        router.terminate()
        router.wait(30)
        reader.join(10)
    stopped = re.search(r"router stopped \((\d+) messages denied\)", "".join(lines))
    assert stopped is not None and int(stopped[1]) >= 6, lines
