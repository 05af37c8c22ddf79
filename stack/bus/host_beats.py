"""The beats of a vehicle's hosts, and which of them are late or lost.

A vehicle spread over several machines has a supervisor on each (:mod:`stack.bus.supervisors`). Each puts a
beat on ``stack/<vehicle>/@supervisor/<host>/beat`` every BEAT_PERIOD_S, through its host's router. Whoever
needs to know whether the other hosts are there (the other supervisors, the commander) watches the beats:

* a host is *late* when its last beat is older than LATE_US (three beats missed): whatever it sends may be
  missing, and what its modules stopped sending is not yet their own failure;
* it is *lost* when its last beat is older than the lease (the profile's ``[bus] host_lease_ms``), or at once when
  its supervisor says it stops (a last beat carrying STOPPING), and *back* with its next beat.

Zenoh itself notices a silent link only after its own lease (10 s by default), and a shorter Zenoh lease drops
healthy loopback links of a loaded machine; the beats decide sooner, and only about hosts. A host never heard is
neither late nor lost (not started yet: ``stack status`` names it). Beats of hosts the profile does not name are
counted and ignored. Times are the watcher's own clock: no clock is compared across hosts.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

from stack.bus import keys

BEAT_PERIOD_S = 0.1
LATE_US = 300_000
DEFAULT_LEASE_MS = 750
"""Loss noticed 0.65–0.75 s after the last beat (within PX4's 1 s estimate timeouts), at 7 missed beats."""
MIN_LEASE_MS = 500
LOST_PREFIX = "Lost host"
STOPPING = b"stopping"
"""The payload of a supervisor's last beat: its host stops (``stack down``), no need to wait for the lease."""


def beat_key(vehicle: str, host: str) -> str:
    return keys.supervisor_key(vehicle, host, "beat")


def beats_key(vehicle: str) -> str:
    return keys.supervisor_query(vehicle, "beat")


def beat_host(key: str, vehicle: str) -> str | None:
    """``stack/<vehicle>/@supervisor/<host>/beat`` → host, or None when the key is not a beat of this vehicle."""
    parts = key.split("/")
    if len(parts) != 5 or parts[:3] != [keys.ROOT, vehicle, "@supervisor"] or parts[4] != "beat":
        return None
    return parts[3]


class HostChange(NamedTuple):
    host: str
    lost: bool
    """True: the host is lost (no beat for the lease); False: it is back."""
    modules: tuple[str, ...]
    silent_us: int
    """How long the host had been silent when the change was seen."""
    stopped: bool = False
    """Lost because its supervisor said it stops."""

    def describe(self) -> str:
        if self.lost:
            names = ", ".join(self.modules) or "no modules"
            why = "its supervisor stopped" if self.stopped else f"no beat for {self.silent_us / 1e6:.2f} s"
            return f"{LOST_PREFIX} {self.host} ({why}): {names}"
        return f"Host {self.host} back after {self.silent_us / 1e6:.1f} s"


class HostWatch:
    """The other hosts of one vehicle, as their beats arrive (see the module docstring).

    ``placement``: host → the vehicle's modules on it (every host of the profile); ``own``: the watcher's host,
    never watched. Feed :meth:`beat` with each beat and its arrival time, and call :meth:`update` regularly.
    """

    def __init__(self, placement: Mapping[str, Sequence[str]], own: str, lease_ms: int) -> None:
        self.placement = {h: tuple(m) for h, m in placement.items() if h != own}
        self.lease_us = lease_ms * 1000
        self.foreign = 0
        """Beats from hosts the profile does not name."""
        self._last: dict[str, int] = {}
        self._lost: dict[str, int] = {}
        """Lost host → its last beat."""
        self._stopping: set[str] = set()

    def beat(self, host: str, now_us: int, payload: bytes = b"") -> None:
        if host not in self.placement:
            self.foreign += 1
            return
        if payload == STOPPING:
            self._stopping.add(host)
            return
        self._stopping.discard(host)
        self._last[host] = max(now_us, self._last.get(host, now_us))

    def update(self, now_us: int) -> list[HostChange]:
        """The hosts lost or back since the last call."""
        changes = []
        for host, last in list(self._last.items()):  # beats may arrive on another thread meanwhile
            silent = now_us - last
            if host in self._lost:
                if last > self._lost[host]:
                    changes.append(HostChange(host, False, self.placement[host], last - self._lost[host]))
                    del self._lost[host]
            elif silent > self.lease_us or host in self._stopping:
                self._lost[host] = last
                changes.append(HostChange(host, True, self.placement[host], silent, host in self._stopping))
        return changes

    @property
    def lost(self) -> list[str]:
        """The lost hosts, in the profile's order."""
        return [h for h in self.placement if h in self._lost]

    def late(self, now_us: int) -> list[str]:
        """The hosts heard before whose last beat is older than LATE_US, and the lost ones."""
        return [
            h for h in self.placement if h in self._lost or (h in self._last and now_us - self._last[h] > LATE_US)
        ]

    def modules_of(self, hosts: Sequence[str]) -> tuple[str, ...]:
        return tuple(m for h in hosts for m in self.placement[h])
