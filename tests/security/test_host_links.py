"""A profile's ``[security] keystore`` puts the links between its hosts on mutual TLS (stack.security.tls): each
host's router listens and connects over ``tls/`` presenting its own identity, and a router without an identity of
the keystore gets nothing through."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest
import zenoh

from stack.bus.config import BusConfig, open_router
from stack.bus.ports import free_port
from stack.security.keystore import init_keystore, issue_identity
from stack.security.tls import tls_files
from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import REPO, stack_env, write_profile


def hosts_profile(tmp_path: Path, keystore: Path, ports: dict[str, int]) -> Path:
    hosts = "\n".join(f'[hosts.{h}]\nendpoint = "tcp/127.0.0.1:{p}"\n' for h, p in ports.items())
    return write_profile(
        tmp_path / "secure.toml", f'extends = "sitl_quad_hosts"\n\n[security]\nkeystore = "{keystore}"\n\n{hosts}'
    )


def router_of(profile, host: str) -> zenoh.Session:
    listen, connect = profile.router_links(host)
    bus = BusConfig(mode="router", listen=listen, connect=connect, tls=profile.host_tls(host))
    return open_router(bus, f"router-{host}", profile.router_link_count)


def test_hosts_link_over_mutual_tls_and_a_router_without_an_identity_gets_nothing(tmp_path: Path) -> None:
    keystore, other = tmp_path / "keys", tmp_path / "other"
    init_keystore(keystore)
    init_keystore(other)
    for host in ("sim", "control", "ground"):
        issue_identity(keystore, host, "host")
    issue_identity(other, "sim", "host")
    ports = {h: free_port() for h in ("sim", "control", "ground")}
    profile = load_profile(str(hosts_profile(tmp_path, keystore, ports)))
    listen, connect = profile.router_links("control")
    assert listen[0].startswith(f"tls/127.0.0.1:{ports['control']}")
    assert connect[0].startswith(f"tls/127.0.0.1:{ports['sim']}")
    sim, control = router_of(profile, "sim"), router_of(profile, "control")
    got: list[str] = []
    arrived = threading.Event()

    def on_sample(sample: zenoh.Sample) -> None:
        got.append(sample.payload.to_string())
        arrived.set()

    sub = sim.declare_subscriber("stack/v1/probe", on_sample)
    try:
        for _ in range(100):  # until the control host's router has linked to the simulator's
            control.put("stack/v1/probe", "control")
            if arrived.wait(0.1):
                break
        assert got and got[0] == "control"
        # A router presenting an identity of another keystore under a host's name is refused at connection.
        rogue_bus = BusConfig(
            mode="router",
            listen=(f"tls/127.0.0.1:{free_port()}",),
            connect=(profile.router_links("control")[1][0],),
            tls={
                "root_ca": str(keystore / "ca.pem"),
                "certificate": str(other / "identities" / "sim.pem"),
                "private_key": str(other / "identities" / "sim.key"),
            },
        )
        rogue = zenoh.open(rogue_bus.zenoh_config("rogue"))
        try:
            got.clear()
            for _ in range(10):
                rogue.put("stack/v1/probe", "rogue")
                threading.Event().wait(0.1)
            assert "rogue" not in got
        finally:
            rogue.close()
    finally:
        sub.undeclare()
        control.close()
        sim.close()


def tool(home: Path, *args: str, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "stack", *args], env={**stack_env(home), **env}, capture_output=True, text=True,
        timeout=60, cwd=REPO,
    )  # fmt: skip


def test_a_tool_joins_a_host_over_mutual_tls_only_with_an_identity_of_its_keystore(tmp_path: Path) -> None:
    keystore, other = tmp_path / "keys", tmp_path / "other"
    init_keystore(keystore)
    init_keystore(other)
    issue_identity(keystore, "sim", "host")
    issue_identity(keystore, "alice", "operator")
    issue_identity(other, "mallory", "operator")
    endpoint = f"tls/127.0.0.1:{free_port()}"
    bus = BusConfig(mode="router", listen=(endpoint,), tls=tls_files(keystore, "sim"))
    router = open_router(bus, "router-sim", 0)
    try:
        out = tool(tmp_path, "vehicles", "--endpoint", endpoint)
        assert out.returncode == 2
        assert out.stderr.strip() == (
            f"error: {endpoint} admits only identities of its keystore: "
            "give `stack --keystore DIR --identity NAME ...` (or set STACK_KEYSTORE and STACK_IDENTITY)"
        )
        out = tool(tmp_path, "--keystore", str(keystore), "--identity", "alice", "vehicles", "--endpoint", endpoint)
        assert "did not admit" not in out.stderr and "Traceback" not in out.stderr, out.stderr
        out = tool(tmp_path, "vehicles", "--endpoint", endpoint, STACK_KEYSTORE=str(other), STACK_IDENTITY="mallory")
        assert out.returncode == 1 and "did not admit identity mallory" in out.stderr, out.stderr
    finally:
        router.close()


def test_a_keystore_or_an_identity_that_is_not_there_is_named_before_anything_starts(tmp_path: Path) -> None:
    keystore = tmp_path / "keys"
    ports = {"sim": free_port(), "control": free_port(), "ground": free_port()}
    with pytest.raises(ProfileError, match=r"security\.keystore: no keystore at .*keys \(make one with"):
        load_profile(str(hosts_profile(tmp_path, keystore, ports)))
    init_keystore(keystore)
    issue_identity(keystore, "sim", "host")
    issue_identity(keystore, "control", "operator")
    profile = load_profile(str(hosts_profile(tmp_path, keystore, ports)))
    profile.check_host("sim")
    with pytest.raises(ProfileError, match=r"security\.keystore: .*identity control is an operator, not a host"):
        profile.check_host("control")
    with pytest.raises(ProfileError, match=r"security\.keystore: .*no identity ground"):
        profile.check_host("ground")
    assert profile.count_denials  # each router counts what its access rules drop, unless told not to
    text = hosts_profile(tmp_path, keystore, ports).read_text()
    (tmp_path / "quiet.toml").write_text(text.replace("[security]\n", "[security]\ncount_denials = false\n"))
    assert not load_profile(str(tmp_path / "quiet.toml")).count_denials
    (tmp_path / "wrong.toml").write_text(text.replace("[security]\n", '[security]\ncount_denials = "no"\n'))
    with pytest.raises(ProfileError, match=r"security\.count_denials"):
        load_profile(str(tmp_path / "wrong.toml"))
