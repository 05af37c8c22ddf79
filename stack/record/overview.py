"""What ``stack log info`` shows: a recording's provenance, span, and per-topic counts and rates."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from stack.record.recorder import RecordingReader


@dataclass
class TopicOverview:
    topic: str
    instance: int
    type: str
    count: int
    rate_hz: float  # mean over the whole recording
    publishers: list[str]  # module names (8-hex-digit ids of publishers not of the run: tools)
    undecoded: int  # messages kept as raw payloads or of a schema this build lacks
    notes: list[str]


@dataclass
class RecordingOverview:
    path: str
    size_bytes: int
    complete: bool
    vehicle: str
    profile: str
    seed: int | None
    lockstep: bool
    clock: str
    start_time: str
    git_commit: str
    stack_version: str
    host: str
    duration_s: float
    start_us: int
    end_us: int
    message_count: int
    topics: list[TopicOverview]
    warnings: list[str]

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def overview(reader: RecordingReader) -> RecordingOverview:
    """Summarise a recording (reads only the summary of a complete file; scans a cut one)."""
    summary = reader.summary()
    duration = summary.duration_s
    rows: dict[tuple[str, int], TopicOverview] = {}
    for c in sorted(summary.channels, key=lambda c: (c.topic, c.instance, c.id)):
        row = rows.get((c.topic, c.instance))
        if row is None:
            row = TopicOverview(c.topic, c.instance, c.type_name, 0, 0.0, [], 0, [])
            rows[(c.topic, c.instance)] = row
        row.count += c.message_count
        publisher = reader.info.publisher_name(c.publisher_id)
        if publisher not in row.publishers:
            row.publishers.append(publisher)
        if not c.decodable:
            row.undecoded += c.message_count
            note = c.raw_reason or f"schema {c.fingerprint:016x} differs from this build's"
            if note not in row.notes:
                row.notes.append(note)
        if not row.type and c.type_name:
            row.type = c.type_name
    for row in rows.values():
        row.rate_hz = row.count / duration if duration > 0 else 0.0
    info = reader.info
    return RecordingOverview(
        path=str(reader.path),
        size_bytes=reader.size,
        complete=reader.complete,
        vehicle=info.vehicle,
        profile=info.profile,
        seed=info.seed,
        lockstep=info.lockstep,
        clock=info.clock,
        start_time=info.start_iso,
        git_commit=info.git_commit,
        stack_version=info.stack_version,
        host=info.host,
        duration_s=duration,
        start_us=summary.start_us,
        end_us=summary.end_us,
        message_count=summary.message_count,
        topics=list(rows.values()),
        warnings=list(reader.warnings),
    )
