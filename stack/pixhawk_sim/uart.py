"""A UART's byte rate on a pseudo-terminal, which would otherwise carry any rate the processes can write.

A 921600-baud 8N1 line carries 10 bits per byte (start, 8 data, stop): 92,160 bytes/s each way.
:class:`UartPacer` is one direction of that line: bytes wait in a buffer and leave at the line rate. The
Pixhawk's transmit side queues whole frames in :data:`TX_BUFFER_BYTES` and drops (and counts) a frame that does
not fit, as PX4's MAVLink streams skip a message when ``get_free_tx_buf()`` is short rather than send half of it.
The receive side stands for the companion's own UART: what it writes into the pty waits in
:data:`RX_BUFFER_BYTES` (its serial driver's buffer) and arrives at the line rate; bytes beyond it are lost.
An idle line accumulates no credit: after a pause bytes again leave at the line rate, not in a burst.
"""

from __future__ import annotations

from dataclasses import dataclass

from stack.mavlink.endpoint import DEFAULT_BAUD

BITS_PER_BYTE = 10
"""8N1: a start bit, 8 data bits, a stop bit."""
TX_BUFFER_BYTES = 4096
"""The serial driver's buffer (NuttX boards give a TELEM port's TX buffer a few KB): ~44 ms at 921600 baud."""
RX_BUFFER_BYTES = 65536
"""The companion's side (a tty's transmit buffer and more): only a writer far beyond the line rate loses bytes."""


@dataclass
class UartCounters:
    bytes_in: int = 0
    bytes_out: int = 0
    frames_dropped: int = 0
    bytes_dropped: int = 0
    max_queued: int = 0


class UartPacer:
    """One direction of a UART (see the module docstring). Times in seconds, any monotonic origin."""

    def __init__(self, baud: int = DEFAULT_BAUD, buffer_bytes: int = TX_BUFFER_BYTES) -> None:
        if baud <= 0 or buffer_bytes <= 0:
            raise ValueError(f"baud and buffer must be > 0, got {baud}, {buffer_bytes}")
        self.bytes_per_s = baud / BITS_PER_BYTE
        self.buffer_bytes = buffer_bytes
        self.counters = UartCounters()
        self._queue = bytearray()
        self._credit = 0.0
        self._last_s: float | None = None

    @property
    def queued(self) -> int:
        return len(self._queue)

    def offer(self, frame: bytes, now_s: float) -> bool:
        """Queue a frame whole; False (dropped, counted) when the buffer cannot take all of it."""
        self._advance(now_s)
        if len(self._queue) + len(frame) > self.buffer_bytes:
            self.counters.frames_dropped += 1
            self.counters.bytes_dropped += len(frame)
            return False
        self._enqueue(frame)
        return True

    def offer_bytes(self, data: bytes, now_s: float) -> None:
        """Queue what fits of a byte stream; the rest is lost (counted in ``bytes_dropped``)."""
        self._advance(now_s)
        room = max(0, self.buffer_bytes - len(self._queue))
        self.counters.bytes_dropped += max(0, len(data) - room)
        self._enqueue(data[:room])

    def _enqueue(self, data: bytes) -> None:
        self._queue += data
        c = self.counters
        c.bytes_in += len(data)
        c.max_queued = max(c.max_queued, len(self._queue))

    def take(self, now_s: float) -> bytes:
        """The bytes the line has carried out of the buffer by ``now_s``."""
        self._advance(now_s)
        n = min(int(self._credit), len(self._queue))
        if n <= 0:
            return b""
        self._credit -= n
        out = bytes(self._queue[:n])
        del self._queue[:n]
        self.counters.bytes_out += n
        return out

    def _advance(self, now_s: float) -> None:
        last = self._last_s
        self._last_s = now_s
        if not self._queue:
            self._credit = 0.0
        elif last is not None and now_s > last:
            self._credit += (now_s - last) * self.bytes_per_s
