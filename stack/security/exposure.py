"""Whether a stack listens beyond its own machine, and the refusal when nothing guards what it lets in.

A router listening on an address other machines reach lets whoever reaches it publish on the vehicle's keys: with a
keystore its links are mutual TLS (stack.security.tls) and only identities of the keystore get in; without one, the
stack refuses to start unless told ``--insecure``, and says why (as SROS2 refuses an unsecured participant where
security is enforced).
"""

from __future__ import annotations

from collections.abc import Iterable

LOOPBACK = ("127.0.0.1", "localhost", "::1", "[::1]")


def address_of(endpoint: str) -> str:
    """The address of a Zenoh endpoint (``tcp/10.0.0.1:7447#so_sndbuf=...`` → ``10.0.0.1``)."""
    locator = endpoint.partition("#")[0].partition("/")[2]
    return locator.rpartition(":")[0] or locator


def beyond_loopback(endpoints: Iterable[str]) -> list[str]:
    """The plain (not ``tls/``) endpoints among ``endpoints`` that listen where other machines reach."""
    return [
        e.partition("#")[0]
        for e in endpoints
        if not e.startswith("tls/") and address_of(e) not in LOOPBACK and not address_of(e).startswith("127.")
    ]


PROFILE_KEYSTORE = "Give the profile a [security] keystore (`stack keys init DIR`, then an identity per host)"


def exposure_problem(what: str, endpoints: Iterable[str], insecure: bool, remedy: str = PROFILE_KEYSTORE) -> str:
    """Why ``what`` may not listen on ``endpoints`` (plain links beyond this machine, not allowed by ``insecure``),
    or '' if it may; ``remedy`` says how to secure it."""
    exposed = beyond_loopback(endpoints)
    if not exposed or insecure:
        return ""
    return (
        f"{what} would listen on {', '.join(exposed)}, beyond this machine, with no keystore: whoever reaches it could "
        f"command the vehicle. {remedy} or, on a network you trust, --insecure"
    )
