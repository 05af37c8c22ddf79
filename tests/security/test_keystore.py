"""The keystore (stack.security.keystore, `stack keys`): an authority, identities it signs with their roles and
addresses, private keys only their owner reads, and a Zenoh link that admits an identity of the keystore and
refuses one without."""

from __future__ import annotations

import json
import stat
from pathlib import Path

import pytest
import zenoh
from cryptography import x509
from cryptography.hazmat.primitives.asymmetric import ec

from stack.bus.ports import free_port
from stack.security.keystore import KeystoreError, init_keystore, issue_identity, list_identities
from tests.support.harness import run_cli


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_an_identity_is_signed_by_the_authority_with_its_role_and_addresses(tmp_path: Path) -> None:
    root = tmp_path / "keys"
    ca_path = init_keystore(root)
    identity = issue_identity(root, "companion", "host", ("10.0.0.2", "companion.local"))
    ca = x509.load_pem_x509_certificate(ca_path.read_bytes())
    cert = x509.load_pem_x509_certificate(identity.cert.read_bytes())
    cert.verify_directly_issued_by(ca)
    assert ca.extensions.get_extension_for_class(x509.BasicConstraints).value.ca is True
    assert identity.role == "host" and identity.name == "companion"
    assert set(identity.names) == {"companion", "10.0.0.2", "companion.local", "localhost", "127.0.0.1"}
    assert isinstance(ca.public_key(), ec.EllipticCurvePublicKey)
    for private in (root / "ca.key", identity.key):
        assert mode(private) == 0o600
    assert mode(root) == mode(root / "identities") == 0o700
    assert [(i.name, i.role) for i in list_identities(root)] == [("companion", "host")]


@pytest.mark.parametrize(
    ("name", "role", "said"),
    [
        ("alice", "pilot", "role 'pilot' is not one of host, operator, observer"),
        ("a/b", "operator", "invalid identity name 'a/b'"),
        ("companion", "host", "identity companion was issued already"),
    ],
)
def test_what_cannot_be_issued_is_refused_saying_why(tmp_path: Path, name: str, role: str, said: str) -> None:
    init_keystore(tmp_path)
    issue_identity(tmp_path, "companion", "host")
    with pytest.raises(ValueError, match=said):
        issue_identity(tmp_path, name, role)
    with pytest.raises(KeystoreError, match="a keystore is already there"):
        init_keystore(tmp_path)
    with pytest.raises(KeystoreError, match="no keystore there"):
        issue_identity(tmp_path / "elsewhere", "bob", "observer")


def test_stack_keys_init_issue_list(tmp_path: Path) -> None:
    root = tmp_path / "keys"
    assert run_cli(tmp_path, "keys", "init", str(root)).returncode == 0
    out = run_cli(tmp_path, "keys", "issue", str(root), "alice", "--role", "operator", "--days", "30")
    assert out.returncode == 0 and out.stdout.startswith("alice (operator) until "), out.stderr
    listed = json.loads(run_cli(tmp_path, "keys", "list", str(root), "--json").stdout)
    assert [(r["name"], r["role"], r["expired"]) for r in listed] == [("alice", "operator", False)]
    out = run_cli(tmp_path, "keys", "issue", str(root), "bob", "--role", "admin")
    assert out.returncode == 2 and out.stderr.strip() == "error: role 'admin' is not one of host, operator, observer"


def tls_config(root: Path, mode_: str, endpoint: str, identity: str | None) -> zenoh.Config:
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(mode_))
    conf.insert_json5("scouting/multicast/enabled", "false")
    tls: dict[str, object] = {"root_ca_certificate": str(root / "ca.pem"), "enable_mtls": True}
    side = "listen" if mode_ == "router" else "connect"
    conf.insert_json5(f"{side}/endpoints", json.dumps([endpoint]))
    if identity is not None:
        tls |= {
            f"{side}_private_key": str(root / "identities" / f"{identity}.key"),
            f"{side}_certificate": str(root / "identities" / f"{identity}.pem"),
        }
    conf.insert_json5("transport/link/tls", json.dumps(tls))
    return conf


def test_a_mutual_tls_link_admits_an_identity_of_the_keystore_and_no_one_else(tmp_path: Path) -> None:
    root, other = tmp_path / "keys", tmp_path / "other"
    init_keystore(root)
    init_keystore(other)
    issue_identity(root, "companion", "host")
    issue_identity(root, "alice", "operator")
    issue_identity(other, "mallory", "operator")
    endpoint = f"tls/127.0.0.1:{free_port()}"
    router = zenoh.open(tls_config(root, "router", endpoint, "companion"))
    try:
        alice = zenoh.open(tls_config(root, "client", endpoint, "alice"))
        alice.close()
        with pytest.raises(zenoh.ZError):
            zenoh.open(tls_config(root, "client", endpoint, None))  # no certificate
        mallory = tls_config(other, "client", endpoint, "mallory")
        mallory.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(root / "ca.pem")))
        with pytest.raises(zenoh.ZError):
            zenoh.open(mallory)  # a certificate of another keystore
    finally:
        router.close()
