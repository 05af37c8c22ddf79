"""A participant on the bus: one Zenoh session, its publishers and subscribers, and its graph tokens."""

from __future__ import annotations

import dataclasses
import logging
import os
import random
import time
import zlib
from collections.abc import Callable

import zenoh

from stack.bus import keys
from stack.bus.config import LOOPBACK_ANY_PORT, BusConfig
from stack.bus.ports import port_taken
from stack.bus.timebase import shared_offset_from_environment
from stack.bus.topics import TopicPublisher, TopicSubscriber
from stack.msg.registry import TOPICS, fingerprint, message_type

_SHARED_OFFSET = shared_offset_from_environment()

if _SHARED_OFFSET is None:

    def wall_clock_us() -> int:
        """Monotonic time in µs, comparable between processes on one host (PX4's hrt_absolute_time)."""
        return time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000

else:

    def wall_clock_us() -> int:
        """Monotonic time in µs on the vehicle's time base (stack.bus.timebase): this host's clock plus the offset
        its supervisor keeps to the leading host's."""
        return time.clock_gettime_ns(time.CLOCK_MONOTONIC) // 1000 + _SHARED_OFFSET.read()


def stable_publisher_id(vehicle: str, name: str) -> int:
    """Publisher ids derived from names are the same in every run, which lockstep ordering relies on."""
    return zlib.crc32(f"{vehicle}/{name}".encode()) or 1


class Node:
    """Owns a Zenoh session. Always close it (``with Node(...)``): zenoh-python can hang at exit otherwise."""

    def __init__(
        self,
        bus: BusConfig,
        vehicle: str,
        name: str,
        *,
        stable_id: bool = True,
        clock: Callable[[], int] = wall_clock_us,
        session: zenoh.Session | None = None,
        run_id: int = 0,
    ) -> None:
        self.vehicle = keys.check_name("vehicle", vehicle)
        self.name = keys.check_name("module", name)
        self.publisher_id = stable_publisher_id(vehicle, name) if stable_id else random.getrandbits(32) | 1
        self.now_us = clock
        self.header_flags = 0
        # The lockstep run this node takes part in (0: none); see stack.bus.topics.HEADER.
        self.run_id = run_id
        self.seq = 0
        self.touched: set[TopicPublisher] = set()
        self.publishers: list[TopicPublisher] = []
        self.subscribers: list[TopicSubscriber] = []
        # Every subscriber not yet withdrawn, and what the withdrawn ones dropped (decode, schema, foreign).
        self.live_subscribers: set[TopicSubscriber] = set()
        self._retired_drops = (0, 0, 0)
        self._tokens: list[zenoh.LivelinessToken] = []
        self._owns_session = session is None
        self.session = session if session is not None else open_session(bus, name)

    def __enter__(self) -> Node:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def on_published(self, pub: TopicPublisher) -> None:
        self.touched.add(pub)

    def publisher(
        self, topic: str, instance: int = 0, *, reliable: bool | None = None, announce: bool = True
    ) -> TopicPublisher:
        msg_type = message_type(topic)
        if reliable is None:
            reliable = not TOPICS[topic].telemetry
        pub = TopicPublisher(self, topic, instance, msg_type, reliable)
        self.publishers.append(pub)
        if announce:
            self.announce("pub", topic, instance)
        return pub

    def subscriber(
        self,
        topic: str,
        instance: int = 0,
        *,
        capacity: int = 256,
        keep_last: bool = False,
        announce: bool = True,
        callback: bool = False,
    ) -> TopicSubscriber:
        sub = TopicSubscriber(self, topic, instance, message_type(topic), capacity, keep_last, callback)
        self.subscribers.append(sub)
        if announce:
            self.announce("sub", topic, instance)
        return sub

    def retire(self, sub: TopicSubscriber) -> None:
        """Keep a withdrawn subscriber's drops in this node's count."""
        if sub in self.live_subscribers:
            self.live_subscribers.discard(sub)
            d, s, f = self._retired_drops
            self._retired_drops = (d + sub.decode_errors, s + sub.schema_errors, f + sub.foreign)

    def drop_counts(self) -> tuple[int, int, int]:
        """Messages every subscriber of this node, withdrawn or not, dropped: undecodable, of another schema
        (or with no stack header), and of another lockstep run."""
        d, s, f = self._retired_drops
        for sub in list(self.live_subscribers):
            d, s, f = d + sub.decode_errors, s + sub.schema_errors, f + sub.foreign
        return d, s, f

    def announce(self, role: str, topic: str, instance: int) -> None:
        """Say in the topic graph that this node publishes or subscribes to a topic (a tool reading a topic
        through its own subscriber must, or a fast-path run does not put the topic on Zenoh for it)."""
        msg_type = message_type(topic)
        key = keys.graph_token(self.vehicle, self.name, role, topic, instance, msg_type.__name__, fingerprint(msg_type))
        self.declare_token(key)

    def declare_token(self, key: str) -> zenoh.LivelinessToken:
        token = self.session.liveliness().declare_token(key)
        self._tokens.append(token)
        return token

    def close(self) -> None:
        if self.session.is_closed():
            return
        for token in self._tokens:
            token.undeclare()
        for sub in self.subscribers:
            sub.undeclare()
        for pub in self.publishers:
            pub.undeclare()
        self._tokens.clear()
        if self._owns_session:
            try:
                self.session.close()
            except zenoh.ZError as e:
                # Zenoh gives up closing after a timeout (e.g. a peer stopped reading); the process exits anyway.
                logging.getLogger("stack.bus").warning("closing the Zenoh session: %s", e)


def open_session(bus: BusConfig, name: str) -> zenoh.Session:
    """A session; a loopback port taken since the supervisor picked it (some other process bound it first) is
    replaced by any free port. The modules started later connect to the endpoint they were given, not to this
    one, and peers reach each other only over links of their own (a router does not relay between two peers),
    so this module then connects to every module of the stack, as a restarted one does."""
    try:
        return zenoh.open(bus.zenoh_config(name))
    except zenoh.ZError as e:
        loopback = bus.listen and all(ep.startswith("tcp/127.0.0.1:") for ep in bus.listen)
        if not (loopback and port_taken(e)):
            raise
        logging.getLogger("stack.bus").warning(
            "%s: %s taken, listening on another port and connecting to every module", name, ", ".join(bus.listen)
        )
        connect = dict.fromkeys(ep for ep in (*bus.connect, *bus.mesh) if ep not in bus.listen)
        moved = dataclasses.replace(bus, listen=(LOOPBACK_ANY_PORT,), connect=tuple(connect))
        return zenoh.open(moved.zenoh_config(name))


def pid_tag() -> str:
    return f"{os.uname().nodename}:{os.getpid()}"
