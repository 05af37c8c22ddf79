"""Writing and reading stack flight recordings (the layout is in :mod:`stack.record.format`).

``RecordingWriter`` turns bus messages into an MCAP file with the mcap library.
``RecordingReader`` reads one back, exactly, and is the stable base of every consumer (replay,
CSV and Rerun export, ``stack log info``)::

    with RecordingReader(path) as reader:
        for m in reader.iter_messages(["vehicle_attitude"]):
            m.topic, m.instance, m.pub_time_us, m.msg.q

A file that is not a stack recording, or whose start is damaged, is refused with a
``RecordingError`` naming the file and the problem. A file whose end is missing (recorder killed,
copy cut short) is read up to the damage: every complete message before it is yielded, and
``reader.warnings`` says where reading stopped.
"""

from __future__ import annotations

import json
import os
import socket
import time
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import msgspec
from mcap.opcode import Opcode
from mcap.records import Channel, Schema
from mcap.writer import LIBRARY_IDENTIFIER, CompressionType

import stack
from stack.bus.node import wall_clock_us
from stack.bus.topics import FLAG_LOCKSTEP_TIME
from stack.msg.registry import TOPICS, fingerprint, schema_text
from stack.record import format as fmt
from stack.record.jsoncodec import JsonMessageCodec, UnsupportedType, codec_for, schema_decoder
from stack.record.mcapscan import (
    MAGIC,
    MESSAGE_HEAD,
    PREFIX,
    RecordError,
    RecordScanner,
    parse_channel,
    parse_header,
    parse_metadata,
    parse_schema,
    read_footer,
    read_summary,
)
from stack.record.mcapwrite import FastMessageWriter
from stack.record.selection import TopicSelection

_msgpack = msgspec.msgpack.Encoder()
_LOW32 = 0xFFFFFFFF


class RecordingError(Exception):
    """A file was refused: the message names the file and what is wrong with it, in one line."""


@dataclass(frozen=True)
class RecordingInfo:
    """What a recording says about itself (its "stack.recording" metadata)."""

    vehicle: str = ""
    profile: str = ""
    seed: int | None = None
    lockstep: bool = False
    start_unix_ns: int = 0
    start_clock_us: int = 0
    host: str = ""
    git_commit: str = ""
    stack_version: str = stack.__version__
    format_version: str = fmt.FORMAT_VERSION
    publishers: dict[int, str] = field(default_factory=dict)
    """The run's modules by publisher id (a tool publishing on the bus has an id of its own, not named here)."""
    extra: dict[str, str] = field(default_factory=dict)

    def publisher_name(self, publisher_id: int) -> str:
        """A publisher's module name, else its id in hex."""
        return self.publishers.get(publisher_id, f"{publisher_id:08x}")

    # start_clock_us is the recording clock (see ``clock``) when start_unix_ns was taken: a real-time
    # recording's log time t happened at UNIX time start_unix_ns / 1000 + (t - start_clock_us) µs.

    @property
    def clock(self) -> str:
        """What log times count: simulated µs (lockstep) or CLOCK_MONOTONIC µs of the recording host."""
        return fmt.CLOCK_LOCKSTEP if self.lockstep else fmt.CLOCK_MONOTONIC

    @property
    def start_iso(self) -> str:
        if not self.start_unix_ns:
            return ""
        seconds = self.start_unix_ns / 1e9
        return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(seconds)) + f".{int(seconds % 1 * 1e3):03d}Z"

    def to_metadata(self) -> dict[str, str]:
        return {
            **self.extra,
            "format_version": self.format_version,
            "vehicle": self.vehicle,
            "profile": self.profile,
            "seed": "" if self.seed is None else str(self.seed),
            "lockstep": "true" if self.lockstep else "false",
            "clock": self.clock,
            "start_time": self.start_iso,
            "start_unix_ns": str(self.start_unix_ns),
            "start_clock_us": str(self.start_clock_us),
            "host": self.host,
            "stack_version": self.stack_version,
            "git_commit": self.git_commit,
            "publishers": json.dumps({f"{k:08x}": v for k, v in sorted(self.publishers.items())}),
            "nonfinite_floats": '"NaN", "-NaN", "Infinity", "-Infinity" (JSON strings)',
        }

    @staticmethod
    def from_metadata(data: Mapping[str, str]) -> RecordingInfo:
        known = {
            "format_version",
            "vehicle",
            "profile",
            "seed",
            "lockstep",
            "clock",
            "start_time",
            "start_unix_ns",
            "start_clock_us",
            "host",
            "stack_version",
            "git_commit",
            "publishers",
            "nonfinite_floats",
        }
        seed = data.get("seed", "")
        return RecordingInfo(
            vehicle=data.get("vehicle", ""),
            profile=data.get("profile", ""),
            seed=int(seed) if seed.lstrip("-").isdigit() else None,
            lockstep=data.get("lockstep") == "true",
            start_unix_ns=_int(data.get("start_unix_ns", "")),
            start_clock_us=_int(data.get("start_clock_us", "")),
            host=data.get("host", ""),
            git_commit=data.get("git_commit", ""),
            stack_version=data.get("stack_version", ""),
            format_version=data.get("format_version", ""),
            publishers=_publishers(data.get("publishers", "")),
            extra={k: v for k, v in data.items() if k not in known},
        )


def _publishers(text: str) -> dict[int, str]:
    """The ``publishers`` metadata (JSON: hex id → module name); what is not that is left out."""
    try:
        data = json.loads(text) if text else {}
    except ValueError:
        return {}
    if not isinstance(data, dict):
        return {}
    out = {}
    for key, name in data.items():
        try:
            out[int(key, 16)] = str(name)
        except ValueError:
            continue
    return out


def new_recording_info(
    vehicle: str,
    profile: str,
    seed: int | None,
    lockstep: bool,
    git_commit: str,
    publishers: dict[int, str] | None = None,
) -> RecordingInfo:
    """The info of a recording starting now on this host (simulated time starts at 0 in lockstep)."""
    return RecordingInfo(
        vehicle=vehicle,
        profile=profile,
        seed=seed,
        lockstep=lockstep,
        start_unix_ns=time.time_ns(),
        start_clock_us=0 if lockstep else wall_clock_us(),
        host=socket.gethostname(),
        git_commit=git_commit,
        publishers=dict(publishers or {}),
    )


# -- writing ---------------------------------------------------------------------------------------


class RecordingWriter:
    """Writes a stack recording: one JSON channel per topic, instance and publisher.

    ``write`` costs about 5 µs per message (JSON encoding, then mcap's chunk builder and zstd,
    which take about half), so one core writes some 200,000 messages a second. Chunks are closed
    at least every ``flush_interval_s`` (checked on writes and by ``flush_if_due``), which bounds
    what a crash loses. Close it (or use it as a context manager) to write the summary.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        info: RecordingInfo,
        *,
        chunk_size: int = 1 << 20,
        flush_interval_s: float = 1.0,
        compression: str = "zstd",
    ) -> None:
        kinds = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
        if compression not in kinds:
            raise ValueError(f"compression must be one of {', '.join(kinds)}, not '{compression}'")
        self.path = Path(path)
        self.info = info
        self.flush_interval_s = flush_interval_s
        self.messages = 0
        self.raw_messages = 0
        self._file: BinaryIO = open(self.path, "wb")  # noqa: SIM115 - owned until close()
        self._mcap = FastMessageWriter(self._file, chunk_size=chunk_size, compression=kinds[compression])
        self._mcap.start(profile="", library=f"stack {stack.__version__}; {LIBRARY_IDENTIFIER}")
        self._mcap.add_metadata(fmt.META_RECORDING, info.to_metadata())
        self._file.flush()
        self._channels: dict[tuple, tuple[int, JsonMessageCodec | None]] = {}
        self._schemas: dict[object, int] = {}
        self._unflushed = 0
        self._last_flush = time.monotonic()
        self._closed = False

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def write(
        self,
        topic: str,
        instance: int,
        msg: msgspec.Struct,
        publisher_id: int,
        index: int,
        pub_time_us: int,
        flags: int,
        log_time_us: int,
    ) -> None:
        """Record one decoded message with its bus header (publisher, topic index, time, flags)."""
        key = (topic, instance, type(msg), publisher_id, flags, index >> 32)
        entry = self._channels.get(key)
        if entry is None:
            entry = self._open_channel(key)
        channel_id, codec = entry
        data = codec.encode(msg) if codec is not None else _msgpack.encode(msg)
        self._add(channel_id, log_time_us, data, pub_time_us, index)

    def write_raw(
        self,
        topic: str,
        instance: int,
        payload: bytes,
        fingerprint: int,
        publisher_id: int,
        index: int,
        pub_time_us: int,
        flags: int,
        log_time_us: int,
        reason: str,
    ) -> None:
        """Record a bus payload this build cannot decode, verbatim, with why (see the format notes)."""
        key = ("raw", topic, instance, fingerprint, publisher_id, flags, index >> 32, reason)
        entry = self._channels.get(key)
        if entry is None:
            entry = self._open_raw_channel(key)
        self.raw_messages += 1
        self._add(entry[0], log_time_us, payload, pub_time_us, index)

    def _add(self, channel_id: int, log_time_us: int, data: bytes, pub_time_us: int, index: int) -> None:
        self._mcap.add_message(
            channel_id,
            log_time_us * 1000 if log_time_us > 0 else 0,
            data,
            pub_time_us * 1000 if pub_time_us > 0 else 0,
            index & _LOW32,
        )
        self.messages += 1
        self._unflushed += 1
        if self._unflushed & 511 == 0:
            self.flush_if_due()

    def _open_channel(self, key: tuple) -> tuple[int, JsonMessageCodec | None]:
        topic, instance, msg_type, publisher_id, flags, epoch = key
        try:
            codec: JsonMessageCodec | None = codec_for(msg_type)
        except UnsupportedType as e:
            codec = None
            reason = f"type has no JSON form: {e}"
        fp = fingerprint(msg_type)
        metadata = _channel_metadata(topic, instance, msg_type.__name__, fp, schema_text(msg_type), publisher_id, flags)
        metadata[fmt.INDEX_EPOCH] = str(epoch)
        if codec is None:
            metadata[fmt.RAW_REASON] = reason
            schema_id = self._raw_schema(msg_type.__name__, fp)
            encoding = fmt.RAW_ENCODING
        else:
            schema_id = self._schemas.get(msg_type)
            if schema_id is None:
                schema_id = self._mcap.register_schema(codec.schema_name, fmt.SCHEMA_ENCODING, codec.schema)
                self._schemas[msg_type] = schema_id
            encoding = fmt.JSON_ENCODING
        channel_id = self._mcap.register_channel(fmt.mcap_topic(topic, instance), encoding, schema_id, metadata)
        entry = (channel_id, codec)
        self._channels[key] = entry
        return entry

    def _open_raw_channel(self, key: tuple) -> tuple[int, None]:
        _, topic, instance, fp, publisher_id, flags, epoch, reason = key
        known = TOPICS.get(topic)
        type_name = known.type.__name__ if known is not None and fingerprint(known.type) == fp else ""
        metadata = _channel_metadata(topic, instance, type_name, fp, "", publisher_id, flags)
        metadata[fmt.INDEX_EPOCH] = str(epoch)
        metadata[fmt.RAW_REASON] = reason
        schema_id = self._raw_schema(type_name or "unknown", fp)
        channel_id = self._mcap.register_channel(fmt.mcap_topic(topic, instance), fmt.RAW_ENCODING, schema_id, metadata)
        entry = (channel_id, None)
        self._channels[key] = entry
        return entry

    def _raw_schema(self, type_name: str, fp: int) -> int:
        key = ("raw", type_name, fp)
        schema_id = self._schemas.get(key)
        if schema_id is None:
            # PlotJuggler needs every channel to have a schema record; an empty encoding means "none".
            schema_id = self._mcap.register_schema(f"{type_name}@{fp:016x}", "", b"")
            self._schemas[key] = schema_id
        return schema_id

    def flush_if_due(self) -> None:
        """Close the current chunk if the flush interval has passed since the last one."""
        if self._unflushed and time.monotonic() - self._last_flush >= self.flush_interval_s:
            self.flush()

    def flush(self) -> None:
        """Write the current chunk to the file now."""
        self._mcap.flush()
        self._unflushed = 0
        self._last_flush = time.monotonic()

    def close(self, end: Mapping[str, str] | None = None) -> None:
        """Write the end metadata, the summary and the footer, and close the file."""
        if self._closed:
            return
        self._closed = True
        try:
            self._mcap.add_metadata(
                fmt.META_END,
                {
                    **(end or {}),
                    "end_unix_ns": str(time.time_ns()),
                    "messages": str(self.messages),
                    "raw_messages": str(self.raw_messages),
                },
            )
            self._mcap.finish()
        finally:
            self._file.close()


def _channel_metadata(
    topic: str, instance: int, type_name: str, fp: int, text: str, publisher_id: int, flags: int
) -> dict[str, str]:
    return {
        fmt.TOPIC: topic,
        fmt.INSTANCE: str(instance),
        fmt.TYPE: type_name,
        fmt.FINGERPRINT: f"{fp:016x}",
        fmt.SCHEMA_TEXT: text,
        fmt.PUBLISHER: f"{publisher_id:08x}",
        fmt.FLAGS: str(flags),
    }


# -- reading ---------------------------------------------------------------------------------------


class RecordedMessage(msgspec.Struct, frozen=True, gc=False):
    """One recorded message with its bus header.

    Exactly one of ``msg``, ``fields`` and ``payload`` is set:

    - ``msg``: the message decoded into this build's Struct (its schema is this build's);
    - ``fields``: a message of a schema this build does not have, as a dict of field values in
      recorded order (arrays as lists), decoded with the recorded JSON Schema;
    - ``payload``: a bus payload that was recorded undecoded (msgpack bytes; see the channel's
      ``raw_reason``).
    """

    topic: str
    instance: int
    log_time_us: int
    pub_time_us: int
    publisher_id: int
    index: int
    flags: int
    fingerprint: int
    msg: Any = None
    fields: dict[str, Any] | None = None
    payload: bytes | None = None

    @property
    def lockstep_time(self) -> bool:
        """Whether ``pub_time_us`` is lockstep simulated time (header flag bit 0)."""
        return bool(self.flags & FLAG_LOCKSTEP_TIME)

    def wire_payload(self) -> bytes:
        """The msgpack payload the bus carried (what replay republishes)."""
        if self.msg is not None:
            return _msgpack.encode(self.msg)
        if self.fields is not None:
            return _msgpack.encode(list(self.fields.values()))
        assert self.payload is not None
        return self.payload


@dataclass(frozen=True)
class ChannelInfo:
    """One recorded channel: a topic instance as sent by one publisher."""

    id: int
    topic: str
    instance: int
    type_name: str
    fingerprint: int
    schema_text: str
    publisher_id: int
    flags: int
    index_epoch: int
    encoding: str
    raw_reason: str
    schema: bytes
    message_count: int

    @property
    def decodable(self) -> bool:
        """Whether its messages decode into this build's Struct (else ``fields`` or ``payload``)."""
        known = TOPICS.get(self.topic)
        return self.encoding == fmt.JSON_ENCODING and known is not None and fingerprint(known.type) == self.fingerprint


@dataclass(frozen=True)
class RecordingSummary:
    """Counts and time span (log times, µs) of a recording."""

    message_count: int
    start_us: int
    end_us: int
    channels: list[ChannelInfo]

    @property
    def duration_s(self) -> float:
        return (self.end_us - self.start_us) / 1e6 if self.message_count else 0.0


class _ChannelReader:
    """Turns the message records of one channel into RecordedMessages."""

    __slots__ = ("_codec", "_decode_fields", "_epoch", "_flags", "_fp", "_instance", "_pub", "_topic", "selected")

    def __init__(self, info: ChannelInfo, selected: bool) -> None:
        self.selected = selected
        self._topic = info.topic
        self._instance = info.instance
        self._fp = info.fingerprint
        self._pub = info.publisher_id
        self._flags = info.flags
        self._epoch = info.index_epoch << 32
        self._codec: JsonMessageCodec | None = None
        self._decode_fields = None
        if info.decodable:
            self._codec = codec_for(TOPICS[info.topic].type)
        elif info.encoding == fmt.JSON_ENCODING:
            self._decode_fields = schema_decoder(info.schema or b"{}")

    def message(self, index: int, log_time_ns: int, pub_time_ns: int, data: bytes) -> RecordedMessage:
        codec = self._codec
        msg = fields = payload = None
        if codec is not None:
            msg = codec.decode(data)
        elif self._decode_fields is not None:
            fields = self._decode_fields(data)
        else:
            payload = data
        return RecordedMessage(
            self._topic,
            self._instance,
            log_time_ns // 1000,
            pub_time_ns // 1000,
            self._pub,
            self._epoch | index,
            self._flags,
            self._fp,
            msg,
            fields,
            payload,
        )


class RecordingReader:
    """Reads a stack recording; refuses anything else with a RecordingError.

    - ``info``: RecordingInfo (vehicle, profile, seed, lockstep, start time, git commit...).
    - ``complete``: the file was closed properly (it has its summary); False for a recording cut
      short, which is still read up to the damage.
    - ``warnings``: what was found damaged so far (one line each, naming the file).
    - ``channels()``, ``summary()``: what is in it (from the summary, or by scanning a cut file).
    - ``iter_messages(topics)``: every message in file order (the recorder's receive order),
      optionally only some topics (``name`` or ``name/instance``).
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.warnings: list[str] = []
        try:
            self._file: BinaryIO = open(self.path, "rb")  # noqa: SIM115 - owned until close()
        except OSError as e:
            raise RecordingError(f"{self.path}: cannot open: {e.strerror or e}") from None
        try:
            self.size = os.fstat(self._file.fileno()).st_size
            self.info = self._read_start()
            self.complete = False
            self._summary_channels: dict[int, Channel] = {}
            self._summary_schemas: dict[int, Schema] = {}
            self._counts: dict[int, int] = {}
            self._span = (0, 0, 0)
            self._statistics = False
            self._read_end()
        except BaseException:
            self._file.close()
            raise
        self._summary: RecordingSummary | None = None

    @classmethod
    def open(cls, path: str | os.PathLike[str]) -> RecordingReader:
        return cls(path)

    def __enter__(self) -> RecordingReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._file.close()

    def _refuse(self, problem: str) -> RecordingError:
        return RecordingError(f"{self.path}: {problem}")

    def _read_start(self) -> RecordingInfo:
        f = self._file
        if self.size == 0:
            raise self._refuse("empty file (0 bytes), not a recording")
        if f.read(len(MAGIC)) != MAGIC:
            raise self._refuse("not an MCAP file (it does not start with the MCAP magic bytes)")
        header = self._next_record("a Header record")
        if header[0] != Opcode.HEADER:
            raise self._refuse(f"corrupt MCAP file: the first record is of type 0x{header[0]:02x}, not a Header")
        try:
            parse_header(header[1])
            opcode, body = self._next_record("the 'stack.recording' metadata")
            metadata = parse_metadata(body) if opcode == Opcode.METADATA else None
        except RecordError as e:
            raise self._refuse(f"corrupt MCAP file: {e}") from None
        if metadata is None or metadata.name != fmt.META_RECORDING:
            raise self._refuse(
                "not a stack recording (an MCAP file without 'stack.recording' metadata; written by another program?)"
            )
        info = RecordingInfo.from_metadata(metadata.metadata)
        if info.format_version.isdigit() and int(info.format_version) > int(fmt.FORMAT_VERSION):
            raise self._refuse(
                f"recording format version {info.format_version} is newer than this build reads ({fmt.FORMAT_VERSION})"
            )
        self._data_start = f.tell()
        return info

    def _next_record(self, what: str) -> tuple[int, bytes]:
        start = self._file.tell()
        prefix = self._file.read(PREFIX.size)
        if len(prefix) < PREFIX.size:
            raise self._refuse(f"truncated: the file ends at byte {self.size}, before {what}")
        opcode, length = PREFIX.unpack(prefix)
        if length > self.size - start - PREFIX.size:
            if opcode in (Opcode.HEADER, Opcode.METADATA):
                raise self._refuse(f"truncated: the file ends at byte {self.size}, inside {what}")
            raise self._refuse(f"corrupt MCAP file: a record at byte {start} claims {length} bytes, beyond the end")
        return opcode, self._file.read(length)

    def _read_end(self) -> None:
        footer = read_footer(self._file, self.size)
        if footer is None:
            self.warnings.append(
                f"{self.path}: incomplete recording (no summary at its end: the recorder was stopped abruptly or "
                "the file was cut); reading what is intact"
            )
            return
        try:
            summary = read_summary(self._file, footer)
        except RecordError as e:
            self.warnings.append(f"{self.path}: damaged summary ({e}); scanning the whole file instead")
            return
        self.complete = True
        self._summary_channels = summary.channels
        self._summary_schemas = summary.schemas
        stats = summary.statistics
        if stats is not None:
            self._statistics = True
            self._counts = dict(stats.channel_message_counts)
            self._span = (stats.message_count, stats.message_start_time // 1000, stats.message_end_time // 1000)

    # -- what is in it ---------------------------------------------------------------------------

    def channels(self) -> list[ChannelInfo]:
        return self.summary().channels

    def summary(self) -> RecordingSummary:
        """Message counts per channel and the time span: from the file's summary, or by a scan."""
        if self._summary is None:
            if self._statistics:
                channels = [
                    _channel_info(c, self._summary_schemas, self._counts.get(c.id, 0))
                    for c in self._summary_channels.values()
                ]
                count, start, end = self._span
                self._summary = RecordingSummary(count, start, end, channels)
            else:
                self._summary = self._count_messages()
        return self._summary

    def _count_messages(self) -> RecordingSummary:
        channels: dict[int, Channel] = {}
        schemas: dict[int, Schema] = {}
        counts: dict[int, int] = {}
        total = 0
        start = end = 0
        for opcode, body in self._scan():
            if opcode == Opcode.MESSAGE:
                channel_id, _, log_time, _ = MESSAGE_HEAD.unpack_from(body)
                if channel_id not in channels:
                    continue
                counts[channel_id] = counts.get(channel_id, 0) + 1
                log_us = log_time // 1000
                start = log_us if total == 0 else min(start, log_us)
                end = max(end, log_us)
                total += 1
            elif opcode == Opcode.CHANNEL:
                self._take_channel(body, channels)
            elif opcode == Opcode.SCHEMA:
                self._take_schema(body, schemas)
        infos = [_channel_info(c, schemas, counts.get(c.id, 0)) for c in channels.values()]
        return RecordingSummary(total, start, end, infos)

    # -- messages --------------------------------------------------------------------------------------

    def iter_messages(self, topics: Iterable[str] | TopicSelection | None = None) -> Iterator[RecordedMessage]:
        """Every recorded message (of the selected topics), decoded exactly, in file order.

        Messages that fail to decode (data damaged inside an intact chunk) are skipped and counted
        in ``warnings``. Each call reads the file afresh.
        """
        selection = topics if isinstance(topics, TopicSelection) else TopicSelection(topics or ())
        schemas: dict[int, Schema] = dict(self._summary_schemas)
        channels: dict[int, Channel] = dict(self._summary_channels)
        readers = {cid: self._channel_reader(c, schemas, selection) for cid, c in channels.items()}
        bad = 0
        orphans = 0
        head_size = MESSAGE_HEAD.size
        for opcode, body in self._scan():
            if opcode == Opcode.MESSAGE:
                channel_id, index, log_time, pub_time = MESSAGE_HEAD.unpack_from(body)
                reader = readers.get(channel_id)
                if reader is None:
                    orphans += 1
                    continue
                if not reader.selected:
                    continue
                try:
                    yield reader.message(index, log_time, pub_time, body[head_size:])
                except (msgspec.DecodeError, TypeError, ValueError):
                    bad += 1
            elif opcode == Opcode.CHANNEL:
                channel = self._take_channel(body, channels)
                if channel is not None and channel.id not in readers:
                    readers[channel.id] = self._channel_reader(channel, schemas, selection)
            elif opcode == Opcode.SCHEMA:
                self._take_schema(body, schemas)
        if bad:
            self._warn(f"{self.path}: {bad} damaged messages could not be decoded and were skipped")
        if orphans:
            self._warn(f"{self.path}: {orphans} messages of channels whose definition was lost were skipped")

    def _channel_reader(
        self, channel: Channel, schemas: dict[int, Schema], selection: TopicSelection
    ) -> _ChannelReader:
        info = _channel_info(channel, schemas, 0)
        return _ChannelReader(info, (info.topic, info.instance) in selection)

    def _take_channel(self, body: bytes, channels: dict[int, Channel]) -> Channel | None:
        try:
            channel = parse_channel(body)
        except RecordError as e:
            self._warn(f"{self.path}: skipped a damaged channel record ({e})")
            return None
        channels.setdefault(channel.id, channel)
        return channel

    def _take_schema(self, body: bytes, schemas: dict[int, Schema]) -> None:
        try:
            schema = parse_schema(body)
        except RecordError as e:
            self._warn(f"{self.path}: skipped a damaged schema record ({e})")
            return
        schemas.setdefault(schema.id, schema)

    def _scan(self) -> Iterator[tuple[int, bytes]]:
        with open(self.path, "rb") as f:
            scanner = RecordScanner(f, self.size, self._data_start)
            count = 0
            for item in scanner:
                if item[0] == Opcode.MESSAGE:
                    count += 1
                yield item
            for warning in scanner.warnings:
                self._warn(f"{self.path}: {warning}")
            if scanner.damage is not None:
                self._warn(
                    f"{self.path}: truncated or damaged: {scanner.damage}; "
                    f"the {count} complete messages before it were read"
                )

    def _warn(self, text: str) -> None:
        if text not in self.warnings:
            self.warnings.append(text)


def _channel_info(channel: Channel, schemas: Mapping[int, Schema], count: int) -> ChannelInfo:
    meta = channel.metadata
    parsed = fmt.parse_mcap_topic(channel.topic)
    topic = meta.get(fmt.TOPIC) or (parsed[0] if parsed else channel.topic)
    instance_text = meta.get(fmt.INSTANCE, "")
    instance = int(instance_text) if instance_text.isdigit() else (parsed[1] if parsed else 0)
    schema = schemas.get(channel.schema_id)
    return ChannelInfo(
        id=channel.id,
        topic=topic,
        instance=instance,
        type_name=meta.get(fmt.TYPE) or (schema.name if schema else ""),
        fingerprint=_hex(meta.get(fmt.FINGERPRINT, "")),
        schema_text=meta.get(fmt.SCHEMA_TEXT, ""),
        publisher_id=_hex(meta.get(fmt.PUBLISHER, "")),
        flags=_int(meta.get(fmt.FLAGS, "")),
        index_epoch=_int(meta.get(fmt.INDEX_EPOCH, "")),
        encoding=channel.message_encoding,
        raw_reason=meta.get(fmt.RAW_REASON, ""),
        schema=schema.data if schema is not None and schema.encoding == fmt.SCHEMA_ENCODING else b"",
        message_count=count,
    )


def _hex(text: str) -> int:
    try:
        return int(text, 16)
    except ValueError:
        return 0


def _int(text: str) -> int:
    return int(text) if text.isdigit() else 0
