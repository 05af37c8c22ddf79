"""Zenoh session configuration with safe defaults.

By default every session is a peer listening on 127.0.0.1 only, with multicast scouting off and
explicit endpoints: it connects to the rendezvous (the supervisor's Zenoh router) and to the modules
started before it, so the modules of a stack form a direct mesh built in start order (gossip's
automatic meshing raced under load and could leave two peers unlinked). Tools join as clients of
the router. A profile may also name router endpoints, so modules on several hosts form one stack
through an ordinary Zenoh router.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import zenoh

from stack.security.denials import Denial, watch_denials

LOOPBACK_ANY_PORT = "tcp/127.0.0.1:0"
DROP_WAIT_US = 50
QUEUE_BATCHES = 16
HOST_LINK_SEND_BUFFER_BYTES = 16384
"""The kernel's send buffer of a TCP link between hosts (Linux doubles it). Telemetry to a ground host behind a slow
link is dropped by Zenoh once this fills: the autotuned default (up to 4 MB) held 14 s of messages at 1 Mbit/s, so
the ground saw the vehicle 14 s late; 32 kB still carries 30 MB/s at a 1 ms round trip."""
ROUTER_LEASE_BETWEEN_HOSTS_MS = 30_000
"""Zenoh's lease on a router of a vehicle spread over hosts. Longer than TCP's retransmission backoff after a link
cut of up to 20 s, so such a cut heals on the same connection: with Zenoh's 10 s, a 6 s cut could already outlast
it (the next retransmission 12.6 s after the cut), and re-opening the transport lost the messages under way (a
lockstep step never finished) and now and then left two routers disagreeing for good (Zenoh 1.10). Losing a host
is the host beats' to notice (stack.bus.host_beats), in under a second."""
QUEUE_PRIORITIES = (
    "control", "real_time", "interactive_high", "interactive_low", "data_high", "data", "data_low", "background"
)  # fmt: skip


ZENOH_RUNTIME_ENV = "ZENOH_RUNTIME"
ZENOH_RX_WORKERS, ZENOH_TX_WORKERS = 2, 1
"""Zenoh 1.10's worker threads for receiving and for sending (zenoh-runtime's ZRuntime defaults)."""


def between_hosts(endpoint: str) -> str:
    """A router's ``endpoint`` towards another host, with the send buffer of HOST_LINK_SEND_BUFFER_BYTES on TCP."""
    if not endpoint.startswith("tcp/"):
        return endpoint
    return f"{endpoint}#so_sndbuf={HOST_LINK_SEND_BUFFER_BYTES}"


def without_link_options(endpoint: str) -> str:
    """``endpoint`` as a person reads it: its address, without the ``#`` link options (:func:`between_hosts`)."""
    return endpoint.partition("#")[0]


@dataclass(frozen=True)
class BusConfig:
    mode: str = "peer"
    connect: tuple[str, ...] = ()
    listen: tuple[str, ...] = (LOOPBACK_ANY_PORT,)
    # Zenoh's low-latency transport saves ~25 % per hop; every session of a stack must agree on it.
    low_latency: bool = True
    # Zenoh's default. A crashed process's links close with its sockets at once; the lease only
    # decides when a silent link counts as dead, and a shorter one dropped links on a loaded machine.
    lease_ms: int = 10000
    gossip: bool = False
    extra: dict[str, object] = field(default_factory=dict)
    tls: dict[str, str] = field(default_factory=dict)
    """Mutual TLS on ``tls/`` links: ``root_ca``, ``certificate`` and ``private_key`` files (stack.security.tls)."""
    access: dict[str, object] = field(default_factory=dict)
    """A router's access rules, Zenoh's ``access_control`` (stack.security.acl); empty: none."""
    mesh: tuple[str, ...] = ()
    """The endpoints of every module process of the stack (a module's own and those it does not connect to as
    well): a module that cannot listen on its own endpoint connects to all the others (stack.bus.node)."""

    def __post_init__(self) -> None:
        if self.mode not in ("peer", "client", "router"):
            raise ValueError(f"bus.mode must be 'peer', 'client' or 'router', not '{self.mode}'")

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @staticmethod
    def from_json(text: str) -> BusConfig:
        d = json.loads(text)
        return BusConfig(
            mode=d["mode"],
            connect=tuple(d["connect"]),
            listen=tuple(d["listen"]),
            low_latency=d["low_latency"],
            lease_ms=d["lease_ms"],
            gossip=d.get("gossip", False),
            extra=d.get("extra", {}),
            tls=d.get("tls", {}),
            access=d.get("access", {}),
            mesh=tuple(d.get("mesh", ())),
        )

    def zenoh_config(self, name: str) -> zenoh.Config:
        conf = zenoh.Config()
        conf.insert_json5("mode", json.dumps(self.mode))
        conf.insert_json5("scouting/multicast/enabled", "false")
        conf.insert_json5("scouting/gossip/enabled", json.dumps(self.gossip))
        conf.insert_json5("scouting/delay", "100")
        conf.insert_json5("listen/endpoints", json.dumps(list(self.listen)))
        conf.insert_json5("connect/endpoints", json.dumps(list(self.connect)))
        conf.insert_json5(
            "connect/retry", json.dumps({"period_init_ms": 50, "period_max_ms": 1000, "period_increase_factor": 2})
        )
        conf.insert_json5("transport/link/tx/lease", str(self.lease_ms))
        # A message that finds its queue full is dropped at once (Zenoh waits 1 ms by default, which behind a slow
        # link, for every message, holds up the sender's thread; a blocking message still waits).
        # Room for a burst of express messages (each its own batch) before a full queue drops one.
        conf.insert_json5("transport/link/tx/queue/size", json.dumps(dict.fromkeys(QUEUE_PRIORITIES, QUEUE_BATCHES)))
        conf.insert_json5(
            "transport/link/tx/queue/congestion_control",
            json.dumps(
                {
                    "drop": {"wait_before_drop": DROP_WAIT_US, "max_wait_before_drop_fragments": 50_000},
                    "block": {"wait_before_close": 5_000_000},
                }
            ),
        )
        # Zenoh's own shared-memory transport keeps files in /dev/shm that outlive a killed process; the
        # stack's same-host traffic has its own fast path (stack.fastpath), which leaves nothing behind.
        conf.insert_json5("transport/shared_memory/enabled", "false")
        if self.low_latency:
            conf.insert_json5("transport/unicast/lowlatency", "true")
            conf.insert_json5("transport/unicast/qos/enabled", "false")
        if self.tls:
            # enable_mtls on both sides: the listener then requires a certificate, and the connector presents one.
            tls = {
                "root_ca_certificate": self.tls["root_ca"],
                "enable_mtls": True,
                "listen_certificate": self.tls["certificate"],
                "listen_private_key": self.tls["private_key"],
                "connect_certificate": self.tls["certificate"],
                "connect_private_key": self.tls["private_key"],
            }
            conf.insert_json5("transport/link/tls", json.dumps(tls))
        if self.access:
            conf.insert_json5("access_control", json.dumps(self.access))
        conf.insert_json5("metadata", json.dumps({"name": name}))
        for key, value in self.extra.items():
            conf.insert_json5(key, json.dumps(value))
        return conf


def open_router(
    bus: BusConfig, name: str, links: int, on_denial: Callable[[Denial], None] | None = None
) -> zenoh.Session:
    """A router session whose Zenoh runtime has, beyond Zenoh's workers, a receiving and a sending worker for each of
    the ``links`` to other routers it may hold; with access rules and ``on_denial``, told of each message they deny
    (stack.security.denials: call it for the process's first session).

    Zenoh closes a TCP link with SO_LINGER at 10 s (zenoh-link-tcp, TCP_LINGER_TIMEOUT): dropping a link to a host
    cut off with data unsent blocks the worker thread that drops it until the link comes back or 10 s pass. With
    Zenoh's two receiving workers, a host cut off from the two others stalled its own router that long, and every
    message between its processes with it. The runtime reads ZENOH_RUNTIME once, as the process's first session
    opens (the router's, in a supervisor or ``stack router``); it is set for that moment only, so the processes
    started afterwards keep Zenoh's defaults, and a ZENOH_RUNTIME given by the user is left as it is."""
    if bus.access and on_denial is not None:
        watch_denials(on_denial)
    if not links or ZENOH_RUNTIME_ENV in os.environ:
        return zenoh.open(bus.zenoh_config(name))
    rx, tx = ZENOH_RX_WORKERS + links, ZENOH_TX_WORKERS + links
    os.environ[ZENOH_RUNTIME_ENV] = f"(rx: (worker_threads: {rx}), tx: (worker_threads: {tx}))"
    try:
        return zenoh.open(bus.zenoh_config(name))
    finally:
        del os.environ[ZENOH_RUNTIME_ENV]
