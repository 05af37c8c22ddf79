"""A stack that would listen beyond its machine over plain links refuses to start unless told --insecure, saying why
(stack.security.exposure); on loopback, or over TLS, it needs neither."""

from __future__ import annotations

from pathlib import Path

from stack.security.exposure import beyond_loopback
from stack.security.keystore import init_keystore, issue_identity
from tests.support.harness import run_cli, write_profile

REFUSED = "beyond this machine, with no keystore: whoever reaches it could command the vehicle"


def test_only_plain_endpoints_other_machines_reach_count() -> None:
    endpoints = [
        "tcp/127.0.0.1:7447",
        "tcp/localhost:1",
        "tcp/[::1]:7447",
        "tls/10.0.0.1:7447",
        "tcp/10.0.0.1:7447#so_sndbuf=65536",
        "tcp/0.0.0.0:7447",
    ]
    assert beyond_loopback(endpoints) == ["tcp/10.0.0.1:7447", "tcp/0.0.0.0:7447"]


def test_a_host_of_a_profile_on_a_network_without_a_keystore_is_refused_before_anything_starts(tmp_path: Path) -> None:
    hosts = "".join(f'[hosts.{h}]\nendpoint = "tcp/10.77.0.{i}:7447"\n' for i, h in enumerate(("sim", "control"), 1))
    profile = write_profile(tmp_path / "plain.toml", f'extends = "sitl_quad_hosts"\n\n{hosts}')
    for command in (("up", str(profile), "--host", "sim"), ("router", str(profile), "--host", "control")):
        out = run_cli(tmp_path, *command, "--duration", "1")
        assert out.returncode == 2, out.stdout + out.stderr
        assert REFUSED in out.stderr and "tcp/10.77.0." in out.stderr and "--insecure" in out.stderr
        assert "Traceback" not in out.stderr
    out = run_cli(tmp_path, "fly", "swarm_formation", "--vehicles", "2", "--here", "v1", "--listen", "tcp/10.77.0.1:1")
    assert out.returncode == 2 and REFUSED in out.stderr, out.stderr
    secure = ("fly", "swarm_formation", "--vehicles", "2", "--here", "v1", "--listen", "tls/10.77.0.1:1")
    out = run_cli(tmp_path, *secure)
    assert out.returncode == 2 and "error: a swarm's hub links over tls/ as a host of a keystore: give `stack " \
        "--keystore DIR --identity NAME fly ...`" in out.stderr, out.stderr  # fmt: skip
    keystore = tmp_path / "keys"
    init_keystore(keystore)
    issue_identity(keystore, "alice", "operator")
    out = run_cli(tmp_path, "--keystore", str(keystore), "--identity", "alice", *secure)
    assert out.returncode == 2 and "identity alice is an operator, not a host" in out.stderr, out.stderr
