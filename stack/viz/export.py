"""Flight recording → Rerun .rrd file, with the same entities and layout as the live plots.

The recording is replayed through :class:`stack.viz.logger.FlightLogger` (no bus, no timing), so an
exported file and a live session differ only in what the time series window shows by default (the
whole flight here) and in the plot rate (every message here; the live bridge decimates for CPU).

``sim_time`` comes from the message timestamps as live. ``wall_time``: a real-time recording's log
times are the recording host's CLOCK_MONOTONIC, mapped to UNIX time by taking the first message as
logged at the recording's start time (off by the delay before that message); a lockstep
recording's are simulated time, so it has no wall time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from stack.mathlib.vector import Vec3

PROGRESS_EVERY = 5000
EXPORT_FLUSH_PERIOD_S = 2.0


class MessageSource(Protocol):
    """What the exporter reads: :class:`stack.record.recorder.RecordingReader` or a stand-in.

    ``iter_messages(topics)`` yields objects with ``topic``, ``instance``, ``log_time_us``,
    ``lockstep_time`` and ``msg`` (None for messages this build cannot decode; they are skipped).
    An ``info`` attribute with ``lockstep``, ``start_unix_ns`` and ``vehicle`` is used when present,
    and ``summary().message_count`` for progress.
    """

    def iter_messages(self, topics: Iterable[str] | None = None) -> Iterator[Any]: ...


@dataclass(frozen=True)
class ExportSummary:
    """Messages read (of the drawn topics), messages drawn, and the flight's span in seconds."""

    messages: int
    drawn: int
    duration_s: float


def export_rrd(
    reader: MessageSource,
    out_path: str | Path,
    progress: Callable[[int, int], None] | None = None,
    *,
    rotors: Sequence[Vec3] | None = None,
    plot_rate_hz: float = 0.0,
    window_s: float | None = None,
) -> ExportSummary:
    """Write ``reader``'s flight as an .rrd file with the live plots' entities and blueprint.

    - ``progress(done, total)`` is called every few thousand messages and at the end (``total`` is
      0 when the reader cannot tell).
    - ``rotors``: rotor hub positions (body FRD, m) for the 3D vehicle; None draws a generic X quad.
    - ``plot_rate_hz``: decimation as in the live bridge (0, the default, keeps every message).
    - ``window_s``: the time series' default window (None: the whole flight).
    """
    from stack.viz.layout import default_blueprint
    from stack.viz.logger import TOPICS, FlightLogger, new_recording

    topics = tuple(t.name for t in TOPICS)
    info = getattr(reader, "info", None)
    total = _message_count(reader, topics) if progress is not None else 0
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    vehicle = getattr(info, "vehicle", "") or "vehicle"
    rec = new_recording(f"{vehicle}-{out.stem}")
    rec.save(out, default_blueprint=default_blueprint(window_s))
    logger: FlightLogger | None = None
    start_unix_us = getattr(info, "start_unix_ns", 0) // 1000
    wall_offset: int | None = None
    first_t = last_t = 0
    count = 0
    try:
        for m in reader.iter_messages(topics):
            count += 1
            if m.msg is None:
                continue
            if logger is None:
                lockstep = bool(getattr(info, "lockstep", False) or m.lockstep_time)
                logger = FlightLogger(
                    rec,
                    plot_rate_hz=plot_rate_hz,
                    flush_period_s=EXPORT_FLUSH_PERIOD_S,
                    time_origin_us=0 if lockstep else None,
                    rotors=rotors,
                )
                if not lockstep and start_unix_us:
                    wall_offset = start_unix_us - m.log_time_us
                first_t = m.msg.timestamp
            last_t = max(last_t, m.msg.timestamp)
            wall = m.log_time_us + wall_offset if wall_offset is not None else None
            logger.log_message(m.topic, m.instance, m.msg, wall)
            if progress is not None and count % PROGRESS_EVERY == 0:
                progress(count, total)
        if logger is not None:
            logger.flush()
    finally:
        rec.flush()
        rec.disconnect()
    if progress is not None:
        progress(count, total)
    drawn = logger.kept if logger is not None else 0
    return ExportSummary(messages=count, drawn=drawn, duration_s=(last_t - first_t) / 1e6)


def _message_count(reader: MessageSource, topics: tuple[str, ...]) -> int:
    """How many messages of ``topics`` the reader holds, if its summary says (else 0)."""
    summary = getattr(reader, "summary", None)
    if summary is None:
        return 0
    try:
        return sum(c.message_count for c in summary().channels if c.topic in topics)
    except (AttributeError, TypeError, ValueError):
        return 0
