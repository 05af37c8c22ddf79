"""A sequential MCAP reader that reads everything intact and says where the damage starts.

mcap's own readers stop with an exception at the first damaged byte, losing a whole cut chunk. A
recorder killed mid-write, or a file copied off a vehicle half-way, still holds every chunk before
the cut, and the cut chunk's compressed prefix still decompresses to its first messages. This
scanner walks the records of the data section (MCAP spec, "Records"), expands chunks, checks
their CRCs, recovers the readable part of a cut chunk and stops at the first record that cannot be
framed, recording what it found in ``damage`` and ``warnings``.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import BinaryIO

import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Header, McapRecord, Metadata, Schema, Statistics

try:
    import lz4.frame as lz4_frame
except ImportError:  # lz4 is optional for mcap; the stack writes zstd
    lz4_frame = None

MAGIC = b"\x89MCAP0\r\n"
PREFIX = struct.Struct("<BQ")
MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence (the stack's topic index), log time, publish time
_CHUNK_HEAD = struct.Struct("<QQQI")  # start time, end time, uncompressed size, uncompressed CRC
_FOOTER = struct.Struct("<QQI")  # summary start, summary offset start, summary CRC
FOOTER_RECORD_SIZE = PREFIX.size + _FOOTER.size
# Records that may appear before the end of the data section (0x80 and up are user records).
_DATA_OPCODES = frozenset(
    {
        Opcode.SCHEMA,
        Opcode.CHANNEL,
        Opcode.MESSAGE,
        Opcode.CHUNK,
        Opcode.MESSAGE_INDEX,
        Opcode.ATTACHMENT,
        Opcode.METADATA,
        Opcode.DATA_END,
    }
)
_PARSE_ERRORS = (McapError, struct.error, UnicodeDecodeError, ValueError, OverflowError)


class RecordError(ValueError):
    """A record's bytes do not parse."""


def parse(record_type: type[McapRecord], body: bytes) -> McapRecord:
    """Parse a record body with mcap's own record classes."""
    try:
        return record_type.read(ReadDataStream(io.BytesIO(body)))
    except _PARSE_ERRORS as e:
        raise RecordError(f"malformed {record_type.__name__} record: {e}") from None


def parse_header(body: bytes) -> Header:
    return parse(Header, body)


def parse_metadata(body: bytes) -> Metadata:
    return parse(Metadata, body)


def parse_schema(body: bytes) -> Schema:
    return parse(Schema, body)


def parse_channel(body: bytes) -> Channel:
    return parse(Channel, body)


@dataclass(frozen=True)
class Footer:
    offset: int
    summary_start: int
    summary_offset_start: int
    summary_crc: int


@dataclass
class Summary:
    """The summary section of a finished file."""

    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    statistics: Statistics | None


def read_footer(f: BinaryIO, size: int) -> Footer | None:
    """The footer of a properly finished file, or None (the writer never reached ``finish``)."""
    tail = FOOTER_RECORD_SIZE + len(MAGIC)
    if size < len(MAGIC) + tail:
        return None
    f.seek(size - tail)
    data = f.read(tail)
    if data[-len(MAGIC) :] != MAGIC:
        return None
    opcode, length = PREFIX.unpack_from(data)
    if opcode != Opcode.FOOTER or length != _FOOTER.size:
        return None
    return Footer(size - tail, *_FOOTER.unpack_from(data, PREFIX.size))


def read_summary(f: BinaryIO, footer: Footer) -> Summary:
    """Schemas, channels and statistics from the summary section; raises RecordError if it is damaged."""
    summary = Summary({}, {}, None)
    if footer.summary_start == 0:
        return summary
    if not 0 < footer.summary_start <= footer.offset:
        raise RecordError(f"summary start {footer.summary_start} is outside the file")
    f.seek(footer.summary_start)
    data = f.read(footer.offset - footer.summary_start)
    if footer.summary_crc:
        footer_fields = PREFIX.pack(Opcode.FOOTER, _FOOTER.size) + struct.pack(
            "<QQ", footer.summary_start, footer.summary_offset_start
        )
        if zlib.crc32(footer_fields, zlib.crc32(data)) != footer.summary_crc:
            raise RecordError("summary CRC mismatch")
    pos = 0
    while pos < len(data):
        if len(data) - pos < PREFIX.size:
            raise RecordError("summary ends inside a record")
        opcode, length = PREFIX.unpack_from(data, pos)
        body = data[pos + PREFIX.size : pos + PREFIX.size + length]
        if len(body) != length:
            raise RecordError("summary ends inside a record")
        if opcode == Opcode.SCHEMA:
            schema = parse_schema(body)
            summary.schemas[schema.id] = schema
        elif opcode == Opcode.CHANNEL:
            channel = parse_channel(body)
            summary.channels[channel.id] = channel
        elif opcode == Opcode.STATISTICS:
            summary.statistics = parse(Statistics, body)
        pos += PREFIX.size + length
    return summary


class RecordScanner:
    """Yields the data-section records of an MCAP file in order, chunks expanded.

    Each item is ``(opcode, body)``. After iteration, ``clean`` says whether the data section ended
    properly (its DataEnd record), ``damage`` describes where reading had to stop, and
    ``warnings`` lists chunks skipped because they were corrupt.
    """

    def __init__(self, f: BinaryIO, size: int, start: int) -> None:
        self._f = f
        self.size = size
        self.start = start
        self.position = start
        self.clean = False
        self.damage: str | None = None
        self.warnings: list[str] = []

    def __iter__(self) -> Iterator[tuple[int, bytes]]:
        f = self._f
        size = self.size
        pos = self.start
        f.seek(pos)
        while True:
            self.position = pos
            if pos == size:
                self.damage = f"the file ends at byte {pos} without the end-of-data record"
                return
            prefix = f.read(PREFIX.size)
            if len(prefix) < PREFIX.size:
                self.damage = f"the file is cut inside a record header at byte {pos}"
                return
            opcode, length = PREFIX.unpack(prefix)
            if opcode not in _DATA_OPCODES and opcode < 0x80:
                self.damage = f"unexpected record type 0x{opcode:02x} at byte {pos} (corrupt data)"
                return
            available = size - pos - PREFIX.size
            if length > available:
                what = "chunk" if opcode == Opcode.CHUNK else "record"
                self.damage = f"the file is cut inside a {what} at byte {pos} ({available} of {length} bytes present)"
                if opcode == Opcode.CHUNK:
                    yield from self._chunk_records(f.read(available), pos, partial=True)
                return
            if opcode == Opcode.DATA_END:
                self.position = pos + PREFIX.size + length
                self.clean = True
                return
            body = f.read(length)
            if opcode == Opcode.CHUNK:
                yield from self._chunk_records(body, pos, partial=False)
            else:
                yield opcode, body
            pos += PREFIX.size + length

    def _chunk_records(self, body: bytes, offset: int, partial: bool) -> Iterator[tuple[int, bytes]]:
        data = self._chunk_data(body, offset, partial)
        pos = 0
        end = len(data)
        while end - pos >= PREFIX.size:
            opcode, length = PREFIX.unpack_from(data, pos)
            start = pos + PREFIX.size
            if length > end - start:
                break
            yield opcode, data[start : start + length]
            pos = start + length
        if pos != end and not partial:
            self.warnings.append(f"chunk at byte {offset} ends inside a record; its last bytes were skipped")

    def _chunk_data(self, body: bytes, offset: int, partial: bool) -> bytes:
        """The uncompressed records of a chunk; of a cut chunk, as much as decompresses."""
        try:
            _, _, uncompressed_size, crc = _CHUNK_HEAD.unpack_from(body)
            (name_length,) = struct.unpack_from("<I", body, _CHUNK_HEAD.size)
            at = _CHUNK_HEAD.size + 4
            compression = body[at : at + name_length].decode()
            at += name_length
            (records_length,) = struct.unpack_from("<Q", body, at)
            at += 8
        except (struct.error, UnicodeDecodeError):
            if not partial:
                self.warnings.append(f"chunk at byte {offset} has a malformed header; skipped")
            return b""
        compressed = body[at : at + records_length]
        try:
            if partial:
                return _decompress_prefix(compression, compressed)
            data = _decompress(compression, compressed, uncompressed_size)
        except (zstandard.ZstdError, RuntimeError, ValueError) as e:
            self.warnings.append(f"chunk at byte {offset} does not decompress ({e}); skipped")
            return b""
        if crc and zlib.crc32(data) != crc:
            self.warnings.append(f"chunk at byte {offset} fails its CRC check (corrupt data); skipped")
            return b""
        return data


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4" and lz4_frame is not None:
        return lz4_frame.decompress(data)
    raise ValueError(f"unsupported chunk compression '{compression}'")


def _decompress_prefix(compression: str, data: bytes) -> bytes:
    """What the beginning of a cut compressed stream decodes to."""
    if compression == "":
        return data
    try:
        if compression == "zstd":
            return zstandard.ZstdDecompressor().decompressobj().decompress(data)
        if compression == "lz4" and lz4_frame is not None:
            return lz4_frame.LZ4FrameDecompressor().decompress(data)
    except (zstandard.ZstdError, RuntimeError, ValueError):
        return b""
    return b""
