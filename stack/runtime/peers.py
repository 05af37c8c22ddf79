"""Reading another vehicle's topic, as a swarm's radio link would carry it (``Module.subscribe_peer``).

A vehicle of a swarm hears another's messages some time after they were sent. A peer input makes that delay
a fixed one: at time ``t`` it gives the newest message the other vehicle published at or before ``t - delay``.
In lockstep every vehicle of a world is at most one step apart (:mod:`stack.runtime.world_clock`), so once a
delay longer than a step and than the other's publication period has passed, the message it stands for has
been published: the reader waits for it (a message published after ``t - delay`` has arrived, the others came
before it, in order) unless the other vehicle has gone, so the same seed gives the same swarm flight. The
wait begins with the first message received, and is given up, with a warning, after PEER_WAIT_S of the wall
clock (a publisher that stopped without its vehicle leaving). On the wall clock a reader takes what has
arrived.
"""

from __future__ import annotations

import bisect
import collections
import logging
import threading
import time
from typing import TYPE_CHECKING, Any

import zenoh

from stack.bus import keys
from stack.bus.node import Node

if TYPE_CHECKING:
    from stack.bus.config import BusConfig
    from stack.bus.topics import TopicSubscriber

log = logging.getLogger("stack.peers")

PEER_WAIT_S = 10.0
"""The longest a lockstep reader waits on the wall clock for a message that is due from a peer still there."""
_WAKE_S = 0.1


class PeerStream:
    """The delay rule on its own: messages in order of publication time (µs), read ``delay_us`` later."""

    def __init__(self, delay_us: int) -> None:
        if delay_us <= 0:
            raise ValueError(f"a peer input's delay must be positive, not {delay_us} µs")
        self.delay_us = delay_us
        self._queued: collections.deque[tuple[int, Any]] = collections.deque()
        self._current: Any = None
        self.newest_us = -1
        """The publication time of the newest message received (-1: none yet)."""

    def add(self, time_us: int, msg: Any) -> None:
        """In order of publication time: a message stamped out of order (a forged one) never holds back the others."""
        if not self._queued or time_us >= self._queued[-1][0]:
            self._queued.append((time_us, msg))
        else:
            bisect.insort(self._queued, (time_us, msg), key=lambda item: item[0])
        self.newest_us = max(self.newest_us, time_us)

    def complete(self, now_us: int) -> bool:
        """Whether every message due at ``now_us`` has arrived: one published after it has (or none ever did)."""
        return self.newest_us < 0 or self.newest_us > now_us - self.delay_us

    def at(self, now_us: int) -> Any:
        """The newest message published at or before ``now_us - delay``, or None."""
        due = now_us - self.delay_us
        queued = self._queued
        while queued and queued[0][0] <= due:
            self._current = queued.popleft()[1]
        return self._current


class PeerInput:
    """One topic of another vehicle on this module's session (see the module docstring).

    Its subscription is announced in the other vehicle's topic graph under ``<own vehicle>-<module>``, so a
    fast-path run there puts the topic on Zenoh for it; messages of any lockstep run are taken (the other vehicle's
    run is not this one). Whether the other vehicle is there is told by its modules' alive tokens.
    """

    def __init__(self, home: Node, bus: BusConfig, vehicle: str, topic: str, delay_us: int, lockstep: bool) -> None:
        """``home``: the reading module's node (its session, vehicle and name)."""
        self.vehicle = vehicle
        self.topic = topic
        self.lockstep = lockstep
        self.stream = PeerStream(delay_us)
        session = home.session
        self._node = Node(bus, vehicle, f"{home.vehicle}-{home.name}", session=session)
        self._sub: TopicSubscriber = self._node.subscriber(topic, callback=True, capacity=4096)
        self._present: set[str] = set()
        self._lock = threading.Lock()
        self._tokens = session.liveliness().declare_subscriber(keys.alive_query(vehicle), self._on_alive, history=True)
        self.gave_up = 0

    def _on_alive(self, sample: zenoh.Sample) -> None:
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._present.add(str(sample.key_expr))
            else:
                self._present.discard(str(sample.key_expr))

    def present(self) -> bool:
        """Whether any module of the other vehicle is running."""
        with self._lock:
            return bool(self._present)

    def read(self, now_us: int) -> Any:
        """The message due at ``now_us`` (None before the first), waiting for it in lockstep."""
        self._drain()
        if self.lockstep and not self.stream.complete(now_us):
            end = time.monotonic() + PEER_WAIT_S
            while not self.stream.complete(now_us) and self.present():
                if time.monotonic() > end:
                    self.gave_up += 1
                    log.warning("%s of %s: nothing since t=%.3f s, due at t=%.3f s: going on without it",
                                self.topic, self.vehicle, self.stream.newest_us / 1e6, now_us / 1e6)
                    break
                self._sub.wait(_WAKE_S)
                self._drain()
        return self.stream.at(now_us)

    def _drain(self) -> None:
        while (item := self._sub.poll()) is not None:
            self.stream.add(item.time_us if item.time_us >= 0 else item.msg.timestamp, item.msg)

    def close(self) -> None:
        self._tokens.undeclare()
        self._node.close()
