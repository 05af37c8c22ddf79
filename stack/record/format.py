"""The layout of a stack flight recording: an MCAP file that Foxglove and PlotJuggler open as is.

- **Header**: profile ``""``, library ``stack <version>; mcap-python <version>``.
- **Metadata "stack.recording"**, written right after the header so that even a cut file has it:
  format version, vehicle, profile, seed, lockstep, the clock of ``log_time`` (``lockstep`` or
  ``monotonic``), start time (UTC, ISO 8601 and Unix ns), host, stack version and git commit, and
  the non-finite float rule.
- **Schemas**: one per message type, encoding ``jsonschema``, named after the type
  (``SensorGyro``); see :mod:`stack.record.jsoncodec`.
- **Channels**: one per (topic, instance, publisher, header flags, index epoch). The MCAP topic
  is ``/<topic>/<instance>`` (``/sensor_gyro/0``); message encoding ``json``. Channel metadata
  keeps what the bus header carried and replay needs: ``stack.topic``, ``stack.instance``,
  ``stack.type``, ``stack.fingerprint`` (16 hex digits), ``stack.schema_text``,
  ``stack.publisher_id`` (8 hex digits), ``stack.flags`` (header flags, bit 0 = lockstep time) and
  ``stack.index_epoch`` (the topic index's bits above 32). A topic has one channel per
  publisher, so it is normally one channel.
- **Messages**: ``publish_time`` = the header's publication time (µs → ns); ``log_time`` = when
  the recorder received it, on the recording's clock: in lockstep runs the simulated time (the
  latest lockstep publication time seen), in real-time runs CLOCK_MONOTONIC. Both tools then plot
  against simulated time for lockstep flights. ``sequence`` = the header's topic index (the
  message's number on its topic for its publisher, 1, 2, ...: MCAP's own "message counter
  assigned by publisher"), low 32 bits (``stack.index_epoch`` holds the rest), so gaps show
  losses. The publisher's sequence number shared by all its topics, which only orders lockstep
  inputs, is not kept; the file keeps the receive order. Publication times below zero, which the
  runtime never produces, are written as 0.
- **Undecodable samples** (a topic this build does not know, a foreign schema fingerprint, a
  malformed payload) are kept too, on channels with message encoding ``msgpack`` holding the bus
  payload unchanged, a schema ``<Type>@<fingerprint>`` with empty encoding, and ``stack.raw``
  saying why. Replay republishes them verbatim. Samples without a stack header are not stack
  messages (every subscriber drops them): they are counted, not recorded; nor are publishers'
  start-up probes (header flag bit 1), which carry no message.
- **Metadata "stack.recording_end"** at a clean stop: end time and counts.
- zstd-compressed chunks, closed at least once a second so a crash loses at most about a second;
  the summary (statistics, chunk indexes, repeated schemas and channels) is written at close.
"""

from __future__ import annotations

FORMAT_VERSION = "1"
META_RECORDING = "stack.recording"
META_END = "stack.recording_end"
JSON_ENCODING = "json"
RAW_ENCODING = "msgpack"
SCHEMA_ENCODING = "jsonschema"

# Channel metadata keys.
TOPIC = "stack.topic"
INSTANCE = "stack.instance"
TYPE = "stack.type"
FINGERPRINT = "stack.fingerprint"
SCHEMA_TEXT = "stack.schema_text"
PUBLISHER = "stack.publisher_id"
FLAGS = "stack.flags"
INDEX_EPOCH = "stack.index_epoch"
RAW_REASON = "stack.raw"

CLOCK_LOCKSTEP = "lockstep"
CLOCK_MONOTONIC = "monotonic"


def mcap_topic(topic: str, instance: int) -> str:
    return f"/{topic}/{instance}"


def parse_mcap_topic(name: str) -> tuple[str, int] | None:
    """``/<topic>/<instance>`` → (topic, instance), or None."""
    parts = name.strip("/").split("/")
    if len(parts) != 2 or not parts[1].isdigit():
        return None
    return parts[0], int(parts[1])
