"""Link faults on demand, on the bytes the simulated Pixhawk sends and receives (below the MAVLink codec).

Each direction is a :class:`FaultChannel` through which every packet passes (a datagram, a frame written, or a
chunk read from a serial line): it is lost while the link is cut, dropped with probability ``drop``, has each
byte's bits flipped with probability ``corrupt`` per byte (one random bit; the receiver's CRC then rejects the
frame), and is delivered ``latency_ms`` ± ``jitter_ms`` (uniform, floored at 0) later, in order, as a serial
line or a queueing network path keeps it. :class:`FaultInjector` holds the settings both directions share, the
cuts (scheduled ``--cut-at``/``--cut-for`` or on demand) and the counters. Seeded, so a test sees the same faults.
"""

from __future__ import annotations

import math
import random
from collections import deque
from dataclasses import asdict, dataclass, fields


@dataclass
class FaultSettings:
    drop: float = 0.0
    """Share of packets dropped, in each direction, [0, 1]."""
    corrupt: float = 0.0
    """Probability per byte of a flipped bit, [0, 1]."""
    latency_ms: float = 0.0
    jitter_ms: float = 0.0

    def check(self) -> None:
        """Raise ValueError naming the first setting out of range."""
        for name in ("drop", "corrupt"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {value}")
        for name in ("latency_ms", "jitter_ms"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be ≥ 0, got {value}")


@dataclass
class ChannelCounters:
    packets: int = 0
    bytes: int = 0
    dropped: int = 0
    """Packets dropped by ``drop``."""
    cut: int = 0
    """Packets lost while the link was cut."""
    corrupted: int = 0
    """Packets with at least one flipped bit."""
    delivered: int = 0


class FaultChannel:
    """One direction of the link (see the module docstring)."""

    def __init__(self, settings: FaultSettings, rng: random.Random) -> None:
        self.settings = settings
        self.rng = rng
        self.counters = ChannelCounters()
        self._queue: deque[tuple[float, bytes]] = deque()
        self._last_due = -math.inf

    def push(self, data: bytes, now_s: float, cut: bool) -> None:
        """A packet enters the channel at ``now_s``."""
        c = self.counters
        c.packets += 1
        c.bytes += len(data)
        s = self.settings
        if cut:
            c.cut += 1
            return
        rng = self.rng
        if s.drop > 0.0 and rng.random() < s.drop:
            c.dropped += 1
            return
        if s.corrupt > 0.0:
            data = self._corrupt(data)
        delay = s.latency_ms
        if s.jitter_ms > 0.0:
            delay = max(0.0, delay + rng.uniform(-s.jitter_ms, s.jitter_ms))
        due = max(now_s + delay * 1e-3, self._last_due)
        self._last_due = due
        self._queue.append((due, data))

    def _corrupt(self, data: bytes) -> bytes:
        rng = self.rng
        p = self.settings.corrupt
        out: bytearray | None = None
        # Geometric gaps between corrupted bytes: one draw per flipped byte rather than one per byte.
        i = self._gap(p)
        while i < len(data):
            if out is None:
                out = bytearray(data)
            out[i] ^= 1 << rng.randrange(8)
            i += 1 + self._gap(p)
        if out is None:
            return data
        self.counters.corrupted += 1
        return bytes(out)

    def _gap(self, p: float) -> int:
        if p >= 1.0:
            return 0
        return int(math.log(1.0 - self.rng.random()) / math.log(1.0 - p))

    def pop_due(self, now_s: float) -> list[bytes]:
        """The packets whose delivery time has come, in order."""
        queue = self._queue
        out = []
        while queue and queue[0][0] <= now_s:
            out.append(queue.popleft()[1])
        self.counters.delivered += len(out)
        return out

    def next_due(self) -> float | None:
        return self._queue[0][0] if self._queue else None


class FaultInjector:
    """Settings, cuts and both directions: ``outbound`` (Pixhawk → companion) and ``inbound``."""

    def __init__(self, settings: FaultSettings | None = None, seed: int = 0) -> None:
        self.settings = settings or FaultSettings()
        self.settings.check()
        rng = random.Random(f"{seed}/link-faults")
        self.outbound = FaultChannel(self.settings, random.Random(rng.random()))
        self.inbound = FaultChannel(self.settings, random.Random(rng.random()))
        self._cuts: list[tuple[float, float]] = []
        self.cut_count = 0

    def configure(self, **changes: float) -> None:
        """Change settings by name (drop, corrupt, latency_ms, jitter_ms); ValueError, changing nothing, on an
        unknown name or a value out of range."""
        known = {f.name for f in fields(FaultSettings)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise ValueError(f"unknown fault setting(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
        candidate = FaultSettings(**{**asdict(self.settings), **{k: float(v) for k, v in changes.items()}})
        candidate.check()
        for name, value in asdict(candidate).items():
            setattr(self.settings, name, value)

    def cut(self, start_s: float, duration_s: float) -> None:
        """Cut the link (both directions) from ``start_s`` for ``duration_s`` seconds."""
        if not (math.isfinite(start_s) and math.isfinite(duration_s) and duration_s >= 0.0):
            raise ValueError(f"a cut needs a finite start and a duration ≥ 0, got {start_s}, {duration_s}")
        self._cuts.append((start_s, start_s + duration_s))
        self.cut_count += 1

    def is_cut(self, now_s: float) -> bool:
        self._cuts = [(a, b) for a, b in self._cuts if b > now_s]
        return any(a <= now_s for a, _ in self._cuts)

    def send(self, data: bytes, now_s: float) -> None:
        self.outbound.push(data, now_s, self.is_cut(now_s))

    def receive(self, data: bytes, now_s: float) -> None:
        self.inbound.push(data, now_s, self.is_cut(now_s))

    def next_due(self) -> float | None:
        times = [t for t in (self.outbound.next_due(), self.inbound.next_due()) if t is not None]
        return min(times) if times else None

    def report(self) -> dict[str, object]:
        return {
            "settings": asdict(self.settings),
            "cuts": self.cut_count,
            "outbound": asdict(self.outbound.counters),
            "inbound": asdict(self.inbound.counters),
        }
