"""``stack log`` (info, export) and ``stack replay``: flight recordings made with ``--record``.

Mounted in the root app as ``app.add_typer(log.app, name="log")`` and ``app.command("replay")(log.replay)``.
"""

from __future__ import annotations

import json
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

import typer

from stack.cli.common import (
    JsonOption,
    command_group,
    fail,
    number,
    output_directory,
    output_file,
    print_table,
    to_jsonable,
)
from stack.record.selection import TopicSelection
from stack.runtime.pacing import Pacer, describe_speed, parse_speed

if TYPE_CHECKING:
    from stack.record.recorder import RecordingReader

# The recording code (mcap and the readers) is imported by the commands that read a recording, so that every
# other `stack` command starts without it.

app = command_group(
    help="Inspect and convert flight recordings (MCAP files written by --record).", no_args_is_help=True
)

FileArgument = typer.Argument(..., help="A recording (.mcap) written by `stack up --record` or `stack fly --record`")
# The vehicle a recording without one is replayed as (the default profile's).
DEFAULT_VEHICLE = "v1"
TopicsOption = typer.Option(
    [], "--topics", "-t", help="Only these topics: name or name/instance, repeatable or comma-separated"
)


def _open(path: Path) -> RecordingReader:
    from stack.record.recorder import RecordingError, RecordingReader

    try:
        return RecordingReader(path)
    except RecordingError as e:
        fail(str(e))


def _selection(topics: list[str]) -> TopicSelection:
    try:
        return TopicSelection(topics)
    except ValueError as e:
        fail(str(e), code=2)


def _warn_all(reader: RecordingReader) -> None:
    for warning in reader.warnings:
        typer.echo(f"warning: {warning}", err=True)


@contextmanager
def _progress(total: int, label: str) -> Iterator[Callable[[int], None]]:
    """A progress bar on stderr advanced by a message count (shown only on a terminal)."""
    with typer.progressbar(length=max(total, 1), label=label, file=sys.stderr, show_pos=True) as bar:
        yield bar.update


def _selected_count(reader: RecordingReader, selection: TopicSelection) -> int:
    return sum(c.message_count for c in reader.channels() if (c.topic, c.instance) in selection)


def _check_selection(reader: RecordingReader, selection: TopicSelection) -> None:
    missing = selection.missing_from((c.topic, c.instance) for c in reader.channels())
    if missing:
        typer.echo(f"warning: not in the recording: {', '.join(missing)}", err=True)


@app.command()
def info(file: Path = FileArgument, as_json: bool = JsonOption) -> None:
    """Vehicle, profile, seed, time span, and each topic's message count and rate."""
    from stack.record.overview import overview

    with _open(file) as reader:
        ov = overview(reader)
    if as_json:
        typer.echo(json.dumps(to_jsonable(ov.to_dict())))
        return
    state = "complete" if ov.complete else "INCOMPLETE (cut short; read up to the damage)"
    typer.echo(f"{ov.path}: {ov.size_bytes / 2**20:.1f} MiB, {state}")
    seed = "?" if ov.seed is None else ov.seed
    clock = "lockstep, simulated time" if ov.lockstep else "real time"
    typer.echo(f"vehicle '{ov.vehicle}', profile {ov.profile or '?'}, seed {seed} ({clock})")
    commit = ov.git_commit[:12] or "unknown"
    typer.echo(f"recorded {ov.start_time or '?'} on {ov.host or '?'}, stack {ov.stack_version}, commit {commit}")
    typer.echo(
        f"duration {ov.duration_s:.3f} s ({ov.start_us / 1e6:.3f} → {ov.end_us / 1e6:.3f} s), "
        f"{ov.message_count} messages on {len(ov.topics)} topics"
    )
    print_table(
        ("TOPIC", "INST", "TYPE", "COUNT", "RATE", "PUBLISHERS", "NOTES"),
        [
            (
                t.topic,
                t.instance,
                t.type or "?",
                t.count,
                f"{t.rate_hz:.1f}",
                ",".join(t.publishers),
                (f"{t.undecoded} undecoded: " + "; ".join(t.notes)) if t.undecoded else "",
            )
            for t in ov.topics
        ],
    )
    for warning in ov.warnings:
        typer.echo(f"warning: {warning}", err=True)


@app.command()
def export(
    file: Path = FileArgument,
    csv_dir: Path | None = typer.Option(
        None, "--csv", callback=output_directory, help="Write one CSV per topic instance into this directory"
    ),
    rrd: Path | None = typer.Option(
        None, "--rrd", callback=output_file, help="Write a Rerun file (.rrd) with the live plots' layout"
    ),
    topics: list[str] = TopicsOption,
) -> None:
    """Convert a recording: --csv DIR (one file per topic instance), --rrd OUT.rrd (Rerun). --topics: CSV only."""
    from stack.record.csvexport import export_csv

    if csv_dir is None and rrd is None:
        fail("nothing to export: give --csv DIR and/or --rrd OUT.rrd", code=2)
    selection = _selection(topics)
    export_rrd = _rrd_exporter() if rrd is not None else None
    with _open(file) as reader:
        _check_selection(reader, selection)
        if csv_dir is not None:
            with _progress(_selected_count(reader, selection), "CSV export") as advance:
                result = export_csv(reader, csv_dir, topics=topics, progress=advance)
            rows = sum(t.rows for t in result.tables)
            typer.echo(f"wrote {len(result.tables)} CSV files ({rows} rows) to {csv_dir}")
            for note in result.notes:
                typer.echo(f"note: {note}", err=True)
        if export_rrd is not None and rrd is not None:
            with _progress(reader.summary().message_count, "Rerun export") as advance:
                export_rrd(reader, rrd, _from_totals(advance))
            typer.echo(f"wrote {rrd}")
        _warn_all(reader)


def _from_totals(advance: Callable[[int], None]) -> Callable[[int, int], None]:
    """Adapt a bar advanced by increments to export_rrd's ``progress(done, total)``."""
    done = 0

    def report(count: int, total: int) -> None:
        nonlocal done
        advance(count - done)
        done = count

    return report


def _rrd_exporter() -> Callable[..., object]:
    """``stack.viz.export.export_rrd(reader, out_path, progress(done, total))``, imported only when asked for."""
    try:
        from stack.viz.export import export_rrd
    except ImportError as e:
        fail(f"--rrd needs stack.viz.export.export_rrd, which this installation does not provide ({e})")
    return export_rrd


def _interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt  # `stack down` (SIGTERM) stops a replay as Ctrl-C does


def replay(
    file: Path = FileArgument,
    speed_text: str = typer.Option(
        "1", "--speed", "-s", help="Time scale: 2 = twice as fast; max (or 0) = as fast as possible"
    ),
    loop: bool = typer.Option(False, "--loop", help="Start over at the end, until Ctrl-C"),
    topics: list[str] = TopicsOption,
    wait_subscribers: float = typer.Option(
        1.0,
        "--wait-subscribers",
        callback=number(0),
        help="Seconds to wait for a subscriber (stack topic echo, stack plot) first",
    ),
) -> None:
    """Republish a recording on a bus of its own, the stack <vehicle>-replay-<pid>, which `stack topic`,
    `stack plot` and scripts attach to with --vehicle and see as live. It never touches a running stack."""
    from stack.cli.replay_stack import ReplayStack
    from stack.record.replay import BusReplayer, replay_pass

    try:
        speed = parse_speed(speed_text)
    except ValueError as e:
        fail(f"--speed: {e}", code=2)
    selection = _selection(topics)
    with _open(file) as reader:
        _check_selection(reader, selection)
        channels = [c for c in reader.channels() if (c.topic, c.instance) in selection]
        total = sum(c.message_count for c in channels)
        if total == 0:
            fail(f"{file}: no messages to replay")
        vehicle = reader.info.vehicle or DEFAULT_VEHICLE
        signal.signal(signal.SIGTERM, _interrupt)
        with ReplayStack(vehicle, reader.info.lockstep, file) as stack:
            typer.echo(f"[stack] replay '{stack.name}' (another terminal attaches with --vehicle {stack.name})")
            replayer = BusReplayer(stack.node)
            sent = 0
            try:
                replayer.declare(channels)
                if not replayer.wait_for_subscribers(wait_subscribers):
                    typer.echo("warning: nobody subscribes to the recorded topics yet; replaying anyway", err=True)
                pace = describe_speed(speed)
                looping = " (looping; Ctrl-C stops)" if loop else ""
                typer.echo(f"replaying {total} messages of vehicle '{vehicle}' {pace}{looping}")
                clock = Pacer(speed)
                passes = 0
                while True:
                    passes += 1
                    with _progress(total, f"replay pass {passes}" if loop else "replay") as advance:
                        sent += replay_pass(reader, replayer, clock, topics=selection, progress=advance)
                    if not loop:
                        break
            except KeyboardInterrupt:
                typer.echo("interrupted", err=True)
            finally:
                time.sleep(0.2)  # let Zenoh deliver the last messages before the session closes
                replayer.close()
        typer.echo(f"replayed {sent} messages")
        _warn_all(reader)
