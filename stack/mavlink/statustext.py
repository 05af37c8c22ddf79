"""Text for a ground station: STATUSTEXT, in chunks when longer than one message holds (I/O-free).

A text longer than STATUSTEXT's 50 characters goes out in chunks sharing a non-zero ``id`` and numbered by
``chunk_seq``; the last chunk is shorter than 50 characters (an empty one follows a text of an exact multiple of
50), as ``common.xml`` defines it and :class:`stack.pixhawk.convert.StatustextAssembler` reads it.

The mavlink module cuts texts at :data:`MAX_CHUNKS` and chunks a text of exactly 50 characters (with the empty
chunk after it); the simulated Pixhawk sends any length, and a text of 50 characters in one message without an id
(``max_chunks=None, one_full_message=True``).
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink2

from stack.pixhawk.convert import STATUSTEXT_CHUNK

MAX_CHUNKS = 8
"""Longer texts are cut (400 characters)."""


class StatustextSender:
    def __init__(self, max_chunks: int | None = MAX_CHUNKS, one_full_message: bool = False) -> None:
        self._next_id = 0
        self._max_bytes = STATUSTEXT_CHUNK * max_chunks if max_chunks is not None else None
        self._single_max = STATUSTEXT_CHUNK if one_full_message else STATUSTEXT_CHUNK - 1
        """The longest text sent as one message (id 0)."""

    def messages(self, severity: int, text: str) -> list[mavlink2.MAVLink_statustext_message]:
        data = text.encode("utf-8", errors="replace")[: self._max_bytes]
        if len(data) <= self._single_max:
            return [mavlink2.MAVLink_statustext_message(severity, data, 0, 0)]
        self._next_id = self._next_id % 0xFFFF + 1
        chunks = [data[i : i + STATUSTEXT_CHUNK] for i in range(0, len(data), STATUSTEXT_CHUNK)]
        if len(chunks[-1]) == STATUSTEXT_CHUNK:
            chunks.append(b"")
        return [mavlink2.MAVLink_statustext_message(severity, c, self._next_id, i) for i, c in enumerate(chunks)]
