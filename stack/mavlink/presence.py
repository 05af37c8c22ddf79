"""Who is on the other end of a link, judged on the wall clock, and the ``telemetry_status`` the commander reads.

PX4's ``telemetry_status`` says whether a ground station (MAV_TYPE_GCS) or an onboard controller has sent a
HEARTBEAT within ``HEARTBEAT_TIMEOUT_US`` (PX4 ``msg/TelemetryStatus.msg``); the commander declares the data link
lost COM_DL_LOSS_T after the last report of a ground station (an onboard controller is not the data link). Here
liveness is judged on the wall clock, where the peers live, and the report is republished every
``TELEMETRY_PERIOD_US`` of wall time while a peer is alive, each stamped with the stack's time: in lockstep the
simulation runs ~10× faster than the wall, so a peer's 1 Hz heartbeat is ~10 s of simulated time apart, and
reporting only on heartbeats would make COM_DL_LOSS_T (simulated seconds) expire between two of them. When the peer
falls silent the reports stop (one last report says so), and the commander's timeout runs on its own clock from the
last one.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from stack.msg.system import TelemetryStatus

HEARTBEAT_TIMEOUT_US = 2_500_000
"""PX4 ``TelemetryStatus.HEARTBEAT_TIMEOUT_US``."""
PEER_TIMEOUT_US = 5_000_000
"""A link counts as used (streams flow, telemetry topics are read) until this long after its last message."""
TELEMETRY_PERIOD_US = 100_000


@dataclass
class _Peer:
    last_us: int = 0
    heartbeat_us: int = 0
    mav_type: int = -1


class Presence:
    """Feed it every message received (``on_message``); ask what to report (``telemetry_due``)."""

    def __init__(self, own: tuple[int, int]) -> None:
        self.own = own
        self.peers: dict[tuple[int, int], _Peer] = {}
        self._reported: tuple[bool, bool] = (False, False)
        self._reported_us = 0

    def on_message(self, source: tuple[int, int], now_us: int, heartbeat_type: int | None = None) -> None:
        """A message from ``source`` (system, component); ``heartbeat_type`` its MAV_TYPE when it is a HEARTBEAT."""
        if source == self.own:
            return
        peer = self.peers.setdefault(source, _Peer())
        peer.last_us = now_us
        if heartbeat_type is not None:
            peer.heartbeat_us = now_us
            peer.mav_type = heartbeat_type

    def _heard(self, mav_type: int, now_us: int) -> bool:
        return any(
            p.mav_type == mav_type and now_us - p.heartbeat_us < HEARTBEAT_TIMEOUT_US for p in self.peers.values()
        )

    def gcs(self, now_us: int) -> bool:
        return self._heard(mavlink2.MAV_TYPE_GCS, now_us)

    def onboard(self, now_us: int) -> bool:
        return self._heard(mavlink2.MAV_TYPE_ONBOARD_CONTROLLER, now_us)

    def active(self, now_us: int) -> bool:
        """Some peer has sent anything lately: the link is in use."""
        return any(now_us - p.last_us < PEER_TIMEOUT_US for p in self.peers.values())

    def peer_count(self, now_us: int) -> int:
        """How many peers sent anything within PEER_TIMEOUT_US."""
        return sum(1 for p in self.peers.values() if now_us - p.last_us < PEER_TIMEOUT_US)

    def telemetry_due(self, now_us: int) -> tuple[bool, bool] | None:
        """(ground station heard, onboard controller heard) to publish now, or None: every TELEMETRY_PERIOD_US
        while either is heard, and once more when both have gone."""
        flags = (self.gcs(now_us), self.onboard(now_us))
        alive = any(flags)
        if not alive and not any(self._reported):
            return None
        if alive and flags == self._reported and now_us - self._reported_us < TELEMETRY_PERIOD_US:
            return None
        self._reported = flags
        self._reported_us = now_us
        return flags


def telemetry_status(endpoint_kind: str, flags: tuple[bool, bool]) -> TelemetryStatus:
    """The ``telemetry_status`` message for :meth:`Presence.telemetry_due`'s flags (PX4's mavlink module publishes
    it per link, ``src/modules/mavlink/mavlink_main.cpp``): the link type UDP for a UDP link, else 0."""
    return TelemetryStatus(
        type=TelemetryStatus.LINK_TYPE_UDP if endpoint_kind.startswith("udp") else 0,
        heartbeat_type_gcs=flags[0],
        heartbeat_type_onboard_controller=flags[1],
    )
