"""Mutual TLS on the links between machines, from a keystore (stack.security.keystore).

A member's identity in the keystore (its certificate and key) is what its router presents, to the routers it
connects to and to those connecting to it; the keystore's authority is the only one it trusts. Zenoh requires the
other side's certificate on every ``tls/`` link (``enable_mtls``, on the listener and on the connector alike), and a
connector checks that the listener's certificate names the host it dialled, so each host's identity is issued with
the addresses of its endpoint (``stack keys issue DIR NAME --role host --address ADDR``).
"""

from __future__ import annotations

from pathlib import Path

from stack.security.keystore import CA_CERT, KeystoreError, read_identity


def tls_files(keystore: Path, identity: str, role: str | None = None) -> dict[str, str]:
    """The files a member presents and trusts (for stack.bus.config.BusConfig.tls), once they are known to be there
    and the identity to have ``role`` (when given); KeystoreError saying what to do otherwise."""
    if not (keystore / CA_CERT).exists():
        raise KeystoreError(f"{keystore}: no keystore there (make one with `stack keys init {keystore}`)")
    found = read_identity(keystore, identity)
    if role is not None and found.role != role:
        raise KeystoreError(f"{keystore}: identity {identity} is an {found.role}, not a {role}")
    if found.expired():
        raise KeystoreError(f"{keystore}: identity {identity} expired on {found.not_after:%Y-%m-%d}; issue a new one")
    if not found.key.exists():
        raise KeystoreError(f"{keystore}: identity {identity} has no private key here ({found.key})")
    return {"root_ca": str(keystore / CA_CERT), "certificate": str(found.cert), "private_key": str(found.key)}


def tls_endpoint(endpoint: str) -> str:
    """``endpoint`` over TLS: a ``tcp/`` endpoint becomes ``tls/`` at the same address and port."""
    return "tls/" + endpoint.removeprefix("tcp/") if endpoint.startswith("tcp/") else endpoint
