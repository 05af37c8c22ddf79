"""A terminal's bytes → keys.

A terminal in cbreak mode sends a printable key as its character, a control key as its control character
(Ctrl-C ``\\x03``, Ctrl-D ``\\x04``) and an arrow as an escape sequence: ``ESC [ A`` (``ESC O A`` in application
cursor mode; with modifiers ``ESC [ 1 ; 5 A``), up, down, right, left for A, B, C, D (ECMA-48 CSI, xterm's
SS3). A sequence may be split between reads, so the decoder keeps an unfinished one until more bytes come, or
:meth:`KeyDecoder.flush` says none will (a lone Esc). Other sequences (function keys) and bytes beyond ASCII
(UTF-8) are dropped.
"""

from __future__ import annotations

ESC = 0x1B
ARROWS = {ord("A"): "up", ord("B"): "down", ord("C"): "right", ord("D"): "left"}
CSI_FINAL = range(0x40, 0x7F)
CSI_BODY = range(0x20, 0x40)
"""A CSI sequence is parameter and intermediate bytes (CSI_BODY), then a final byte; any other byte cuts it."""
CSI_MAX = 64
"""A CSI sequence longer than this is garbage: dropped, not waited on."""


class KeyDecoder:
    def __init__(self) -> None:
        self._pending = bytearray()

    @property
    def pending(self) -> bool:
        """Whether an unfinished escape sequence waits for more bytes."""
        return bool(self._pending)

    def feed(self, data: bytes) -> list[str]:
        """The keys in ``data``: a character, a control character, ``up``/``down``/``left``/``right`` or ``esc``."""
        buf = self._pending + data
        keys: list[str] = []
        i = 0
        while i < len(buf):
            b = buf[i]
            if b != ESC:
                if b < 0x80:
                    keys.append(chr(b))
                i += 1
                continue
            end = _sequence_end(buf, i)
            if end is None:
                break
            if end == i + 1:
                keys.append("esc")
            elif buf[end - 1] in ARROWS:
                keys.append(ARROWS[buf[end - 1]])
            i = end
        self._pending = buf[i:]
        return keys

    def flush(self) -> list[str]:
        """No more bytes are coming now: an unfinished sequence was a lone Esc (and what followed it, keys)."""
        if not self._pending:
            return []
        rest = bytes(self._pending[1:])
        self._pending.clear()
        return ["esc", *self.feed(rest)]


def _sequence_end(buf: bytearray, start: int) -> int | None:
    """Where the escape sequence at ``start`` ends (exclusive), or None if it is not finished yet."""
    if start + 1 >= len(buf):
        return None
    intro = buf[start + 1]
    if intro == ord("O"):  # SS3: one more byte
        return start + 3 if start + 2 < len(buf) else None
    if intro != ord("["):
        return start + 1  # Esc, then an ordinary key
    for j in range(start + 2, min(len(buf), start + CSI_MAX)):
        if buf[j] in CSI_FINAL:
            return j + 1
        if buf[j] not in CSI_BODY:
            return j
    return start + CSI_MAX if len(buf) >= start + CSI_MAX else None
