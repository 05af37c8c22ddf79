"""One simulated clock for the vehicles of a swarm spread over several machines, kept over the bus.

The rule is the world file's (stack.runtime.world_clock): a vehicle's coordinator runs at most SLACK_US ahead of
every other vehicle of the world, and once it must wait, waits until each has finished the step before its own.
Across machines there is no file to share: each coordinator puts the step it has finished on
``stack/<vehicle>/@world/step`` and holds a liveliness token ``stack/<vehicle>/@world/member`` while it takes part.
A vehicle whose token is gone has left the world (its stack ended, or its host was lost: Zenoh drops the token of a
session it no longer reaches) and is waited for no more; one whose token has not appeared yet has not started, and
is waited for.
"""

from __future__ import annotations

import logging
import struct
import threading
import time

import zenoh

from stack.bus import keys
from stack.runtime.world_clock import SLACK_US

log = logging.getLogger("stack.lockstep")

SLOW_WAIT_S = 5.0
_STEP = struct.Struct("<q")


def step_key(vehicle: str) -> str:
    return f"{keys.vehicle_root(vehicle)}/@world/step"


def member_token(vehicle: str) -> str:
    return f"{keys.vehicle_root(vehicle)}/@world/member"


class BusWorldClock:
    """Vehicle ``names[slot]``'s coordinator's side of a world kept over ``session``: :meth:`wait` before each step,
    :meth:`done` after it, :meth:`close` on the way out (the interface of stack.runtime.world_clock.WorldClock)."""

    def __init__(self, session: zenoh.Session, slot: int, names: list[str]) -> None:
        if not 0 <= slot < len(names):
            raise ValueError(f"no slot {slot} in a world of {len(names)} vehicles")
        self.name = names[slot]
        self.others = [n for n in names if n != self.name]
        self._done: dict[str, int] = dict.fromkeys(self.others, 0)
        self._left: set[str] = set()
        self._present: set[str] = set()
        self._changed = threading.Condition()
        block = zenoh.CongestionControl.BLOCK
        self._publisher = session.declare_publisher(step_key(self.name), congestion_control=block)
        self._steps = [session.declare_subscriber(step_key(n), self._on_step) for n in self.others]
        self._members = [
            session.liveliness().declare_subscriber(member_token(n), self._on_member, history=True) for n in self.others
        ]
        self._token = session.liveliness().declare_token(member_token(self.name))

    def _vehicle_of(self, key: str) -> str:
        return key.split("/")[1]

    def _on_step(self, sample: zenoh.Sample) -> None:
        raw = sample.payload.to_bytes()
        if len(raw) != _STEP.size:
            return
        vehicle = self._vehicle_of(str(sample.key_expr))
        with self._changed:
            if vehicle in self._done:
                self._done[vehicle] = max(self._done[vehicle], _STEP.unpack(raw)[0])
                self._changed.notify_all()

    def _on_member(self, sample: zenoh.Sample) -> None:
        vehicle = self._vehicle_of(str(sample.key_expr))
        with self._changed:
            if sample.kind == zenoh.SampleKind.PUT:
                self._present.add(vehicle)
            elif vehicle in self._present:
                self._left.add(vehicle)
                log.warning("world clock: vehicle %s has left: time goes on without it", vehicle)
            self._changed.notify_all()

    def wait(self, t_us: int, period_us: int) -> None:
        """As stack.runtime.world_clock.WorldClock.wait: at most SLACK_US ahead of every other vehicle still in the
        world; once it must wait, until each has finished the steps before ``t_us``."""
        needed = t_us - period_us
        since = time.monotonic()
        warned = False
        with self._changed:
            if not self._laggard(t_us - max(period_us, SLACK_US)):
                return
            while True:
                laggard = self._laggard(needed)
                if laggard is None:
                    return
                self._changed.wait(0.1)
                if not warned and time.monotonic() - since > SLOW_WAIT_S:
                    log.warning("world clock: time waits at t=%.3f s for vehicle %s", t_us / 1e6, laggard)
                    warned = True

    def _laggard(self, needed: int) -> str | None:
        return next((n for n in self.others if n not in self._left and self._done[n] < needed), None)

    def done(self, t_us: int) -> None:
        self._publisher.put(_STEP.pack(t_us))

    def close(self) -> None:
        self._token.undeclare()
        for sub in (*self._steps, *self._members):
            sub.undeclare()
        self._publisher.undeclare()
