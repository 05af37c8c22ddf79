"""Free TCP ports for listeners the stack starts (module endpoints, the rendezvous, viewers).

A port is picked outside the kernel's ephemeral range: the local ports of outgoing connections come
from that range, so a port picked there (for example by binding port 0) can be taken by one of the
many connections modules open to each other before the module that was given it binds it.

A port picked for a listener that starts later is held (:func:`hold_port`: a socket bound to it, not
listening) until just before its listener binds it: a stack starting beside this one then cannot pick
it meanwhile, as it could pick a port that was merely free when looked at.
"""

from __future__ import annotations

import random
import socket
from pathlib import Path

import zenoh

_EPHEMERAL_RANGE_FILE = Path("/proc/sys/net/ipv4/ip_local_port_range")
_DEFAULT_EPHEMERAL = (32768, 60999)
_LOWEST = 10000
_ATTEMPTS = 500
_given: set[int] = set()
_random = random.SystemRandom()


def ephemeral_range() -> tuple[int, int]:
    """The kernel's range of local ports for outgoing connections (inclusive)."""
    try:
        low, high = (int(v) for v in _EPHEMERAL_RANGE_FILE.read_text().split())
        return low, high
    except (OSError, ValueError):
        return _DEFAULT_EPHEMERAL


def hold_port(host: str = "127.0.0.1", kind: socket.SocketKind = socket.SOCK_STREAM) -> socket.socket:
    """A socket bound to a port nobody else had bound (TCP, or UDP with ``kind=SOCK_DGRAM``), below the
    ephemeral range and not given out before by this process. While it is open no other process can bind
    the port; close it right before the listener it was picked for binds it. Not inherited by children."""
    low, high = ephemeral_range()
    candidates = (_LOWEST, low) if low - _LOWEST >= 1000 else (high + 1, 65536)
    for _ in range(_ATTEMPTS):
        port = _random.randrange(*candidates)
        held = None if port in _given else _bound(host, port, kind)
        if held is not None:
            _given.add(port)
            return held
    held = socket.socket(socket.AF_INET, kind)
    held.bind((host, 0))
    return held


def hold_again(port: int, host: str = "127.0.0.1") -> socket.socket | None:
    """Hold the TCP ``port`` a listener of ours left (its process exited, to be restarted), or None if another
    process has bound it since. Bound with SO_REUSEADDR, as Zenoh's listeners are: the connections the old
    listener left in TIME_WAIT do not keep it from being held, and the new listener binds beside it, while
    another process's plain bind (:func:`hold_port`, :func:`free_port`) is refused."""
    return _bound(host, port, socket.SOCK_STREAM, reuse_address=True)


def _bound(host: str, port: int, kind: socket.SocketKind, reuse_address: bool = False) -> socket.socket | None:
    """A socket bound to ``port``, or None if it cannot be bound."""
    s = socket.socket(socket.AF_INET, kind)
    if reuse_address:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        s.bind((host, port))
    except OSError:
        s.close()
        return None
    return s


def free_port(host: str = "127.0.0.1", kind: socket.SocketKind = socket.SOCK_STREAM) -> int:
    """A port nobody has bound now, picked as :func:`hold_port` picks one, for a listener that binds it at once."""
    with hold_port(host, kind) as held:
        return int(held.getsockname()[1])


def port_taken(error: zenoh.ZError) -> bool:
    """Whether Zenoh failed to listen because the port is in use (another process bound it first)."""
    return "in use" in str(error)
