"""mcap's Writer with a message write five times cheaper, for the recorder's hot path.

mcap's own ``add_message`` builds a ``Message`` record object, then writes it field by field
through its record builder (seven ``struct.pack`` calls and a seek back to patch the length):
about 16 of the 23 µs the recorder spent per message (measured with a 100,000-message write).
This writes the same bytes (MCAP spec, "Message" record: opcode, length, channel id,
sequence, log time, publish time, data) with one pack, and keeps the writer's statistics and the
chunk's message index exactly as mcap does. It relies on the private state of mcap's ``Writer``
and ``ChunkBuilder`` (checked against mcap 1.6); when that is not there, mcap's own path is used.
"""

from __future__ import annotations

import struct
from typing import IO

from mcap.opcode import Opcode
from mcap.records import MessageIndex
from mcap.writer import CompressionType, Writer

_MESSAGE_HEAD = struct.Struct("<BQHIQQ")
_MESSAGE_FIELDS = _MESSAGE_HEAD.size - 9


class FastMessageWriter(Writer):
    """A drop-in ``mcap.writer.Writer`` (chunked) whose ``add_message`` skips the record objects."""

    def __init__(self, output: IO[bytes], *, chunk_size: int, compression: CompressionType) -> None:
        super().__init__(output, chunk_size=chunk_size, compression=compression)
        self._chunk_size = chunk_size
        state = self.__dict__
        self._fast = all(name in state for name in ("_Writer__statistics", "_Writer__chunk_builder")) and hasattr(
            state["_Writer__chunk_builder"], "record_writer"
        )

    def add_message(self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int = 0) -> None:
        if not self._fast:
            super().add_message(channel_id, log_time, data, publish_time, sequence)
            return
        stats = self._Writer__statistics  # type: ignore[attr-defined]
        chunk = self._Writer__chunk_builder  # type: ignore[attr-defined]
        if stats.message_count == 0 or log_time < stats.message_start_time:
            stats.message_start_time = log_time
        if log_time > stats.message_end_time:
            stats.message_end_time = log_time
        stats.channel_message_counts[channel_id] += 1
        stats.message_count += 1

        if chunk.num_messages == 0 or log_time < chunk.message_start_time:
            chunk.message_start_time = log_time
        if log_time > chunk.message_end_time:
            chunk.message_end_time = log_time
        buffer = chunk.record_writer._buffer
        offset = buffer.tell()
        index = chunk.message_indices.get(channel_id)
        if index is None:
            index = chunk.message_indices[channel_id] = MessageIndex(channel_id=channel_id, records=[])
        index.records.append((log_time, offset))
        chunk.num_messages += 1
        buffer.write(
            _MESSAGE_HEAD.pack(
                Opcode.MESSAGE, _MESSAGE_FIELDS + len(data), channel_id, sequence, log_time, publish_time
            )
        )
        buffer.write(data)
        if buffer.tell() > self._chunk_size:
            self._Writer__maybe_finalize_chunk()  # type: ignore[attr-defined]
