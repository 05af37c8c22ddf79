"""The supervisor's side of a fast-path run: the region, one eventfd per module, and the words only it writes.

Every module process inherits the region's memfd and all the eventfds (the same numbers in every
process), so none of them has a name anywhere and all are gone with the last process that holds them.
The supervisor also tells the coordinator what it decided about a module that exited (restart or not),
and which topics something outside the fast path subscribes to, from the topic graph's liveliness
tokens: modules of the profile read the fast path, anything else (``stack topic echo``, a ground-station
link, a recorder on another host) needs the topic on Zenoh. A topic that a member over Zenoh reads is there
already: the coordinator's process relays it (:mod:`stack.fastpath.bridge`), and its publisher putting it on
Zenoh as well would deliver every message twice to the others.
"""

from __future__ import annotations

import os
import threading

import zenoh

from stack.bus import keys
from stack.fastpath.layout import (
    H_ROSTER,
    P_NAME,
    P_ZENOH,
    S_AWAY,
    S_EVENTFD,
    S_EXITS,
    S_EXPECTED,
    S_NPUBS,
    S_RESTART,
    Region,
)


class FastPathHost:
    def __init__(self, names: list[str], run_id: int, bridged: list[str] | tuple[str, ...] = ()) -> None:
        self.names = names
        self.bridged = frozenset(bridged)
        self.region = Region.create(names, run_id)
        self.eventfds = [os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC) for _ in names]
        w = self.region.words
        for slot, fd in enumerate(self.eventfds):
            w[self.region.slot_word(slot, S_EVENTFD)] = fd
            w[self.region.slot_word(slot, S_EXPECTED)] = 1
        self._subscribers: dict[str, set[str]] = {}  # topic suffix → modules subscribing, from the graph
        self._lock = threading.Lock()
        self._flags_lock = threading.Lock()
        self._closed = False
        """Set under ``_flags_lock`` before the region is closed: a graph change Zenoh's thread delivers while the
        host closes (undeclaring the subscriber does not wait for a callback already running) flags nothing."""
        self._graph: zenoh.Subscriber | None = None

    def pass_fds(self) -> tuple[int, ...]:
        return (self.region.fd, *self.eventfds)

    def roster_complete(self) -> None:
        self.region.words[H_ROSTER] = 1

    def exit_handled(self, name: str, restarting: bool) -> None:
        """The supervisor's word on a module that exited: lockstep time waits while a restart is pending."""
        slot = self.region.slot_of(name)
        w = self.region.words
        w[self.region.slot_word(slot, S_RESTART)] = int(restarting)
        w[self.region.slot_word(slot, S_EXITS)] += 1

    def host_away(self, names: tuple[str, ...], away: bool) -> None:
        """The host of the modules ``names`` is lost (``away``) or back: while it is away, lockstep time waits for
        its members in this run without judging their step stalled."""
        for name in names:
            if name in self.names:
                self.region.words[self.region.slot_word(self.region.slot_of(name), S_AWAY)] = int(away)

    def restart_over(self, name: str) -> None:
        """A restart succeeded or was given up: time need not wait for it any longer."""
        self.region.words[self.region.slot_word(self.region.slot_of(name), S_RESTART)] = 0

    # -- outside subscribers ---------------------------------------------------------------------

    def watch_graph(self, session: zenoh.Session, vehicle: str) -> None:
        self._graph = session.liveliness().declare_subscriber(
            keys.graph_query(vehicle), self._on_graph_token, history=True
        )

    def _on_graph_token(self, sample: zenoh.Sample) -> None:
        # stack/<vehicle>/@graph/<module>/<role>/<topic>/<instance>/<Type>/<fingerprint>
        parts = str(sample.key_expr).split("/")
        if len(parts) != 9 or parts[4] != "sub":
            return
        module, suffix = parts[3], f"{parts[5]}/{parts[6]}"
        with self._lock:
            modules = self._subscribers.setdefault(suffix, set())
            if sample.kind == zenoh.SampleKind.PUT:
                modules.add(module)
            else:
                modules.discard(module)
        self.update_outside()

    def outside_topics(self) -> list[str]:
        """``topic/instance`` of the topics something outside the profile's modules subscribes to."""
        inside = set(self.names)
        with self._lock:
            return sorted(suffix for suffix, modules in self._subscribers.items() if modules - inside)

    def update_outside(self) -> None:
        """Flag each publication that something outside the profile's modules subscribes to and the bridge does not
        relay (at once when the graph changes; the supervisor calls it again as modules declare new publications)."""
        with self._lock:
            relayed = {suffix for suffix, modules in self._subscribers.items() if modules & self.bridged}
        outside = set(self.outside_topics()) - relayed
        region, w = self.region, self.region.words
        with self._flags_lock:
            if self._closed:
                return
            for slot in range(region.slots):
                for j in range(int(w[region.slot_word(slot, S_NPUBS)])):
                    flag = int(region.read_text(region.pub_word(slot, j, P_NAME)) in outside)
                    word = region.pub_word(slot, j, P_ZENOH)
                    if w[word] != flag:
                        w[word] = flag

    def close(self) -> None:
        if self._graph is not None:
            self._graph.undeclare()
        with self._flags_lock:
            self._closed = True
        self.region.close()
        os.close(self.region.fd)
        for fd in self.eventfds:
            os.close(fd)
