"""A recording as CSV: one file per topic instance, like PX4's ``ulog2csv``.

Each file is named ``<topic>_<instance>.csv`` and has the columns ``log_time_us``,
``pub_time_us``, ``publisher_id`` (8 hex digits) and ``index`` (the message's number on its
topic), then the message fields in schema order with arrays spread over ``field[0]``,
``field[1]``, ... (variable-length arrays get as many columns as their longest value and empty
cells after a shorter one). Booleans are written as 1/0 so that plotting tools read them as
numbers; floats in Python's shortest exact form, with ``nan``, ``inf`` and ``-inf``. Messages
recorded undecoded (foreign payloads) have no fields to spread and are left out, which
``CsvExport.notes`` reports.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import msgspec

from stack.record.recorder import ChannelInfo, RecordingReader
from stack.record.selection import TopicSelection

PROGRESS_EVERY = 1024
_META_COLUMNS = ("log_time_us", "pub_time_us", "publisher_id", "index")
_SCALAR, _BOOL, _ARRAY, _BOOL_ARRAY = 0, 1, 2, 3


@dataclass
class CsvTable:
    """One written CSV file."""

    path: Path
    topic: str
    instance: int
    columns: list[str]
    rows: int = 0


@dataclass
class CsvExport:
    tables: list[CsvTable] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class _Layout:
    """How one schema's fields spread over columns: (name, kind, width) per field."""

    fields: list[tuple[str, int, int]]
    variable: list[int]  # indexes of variable-length arrays, whose width the data decides

    @staticmethod
    def from_schema(schema: bytes) -> _Layout:
        properties: dict[str, dict[str, Any]] = json.loads(schema).get("properties", {}) if schema else {}
        fields: list[tuple[str, int, int]] = []
        variable: list[int] = []
        for i, (name, prop) in enumerate(properties.items()):
            if prop.get("type") == "array":
                lo, hi = prop.get("minItems"), prop.get("maxItems")
                fixed = lo is not None and lo == hi
                kind = _BOOL_ARRAY if prop.get("items", {}).get("type") == "boolean" else _ARRAY
                fields.append((name, kind, int(hi) if fixed else 0))
                if not fixed:
                    variable.append(i)
            else:
                fields.append((name, _BOOL if prop.get("type") == "boolean" else _SCALAR, 1))
        return _Layout(fields, variable)

    def widen(self, index: int, width: int) -> None:
        name, kind, old = self.fields[index]
        if width > old:
            self.fields[index] = (name, kind, width)

    def columns(self) -> list[str]:
        out = list(_META_COLUMNS)
        for name, kind, width in self.fields:
            if kind >= _ARRAY:
                out += [f"{name}[{i}]" for i in range(width)]
            else:
                out.append(name)
        return out

    def row(self, values: Iterable[Any]) -> list[Any]:
        out: list[Any] = []
        for (_, kind, width), v in zip(self.fields, values, strict=False):
            if kind == _SCALAR:
                out.append(v)
            elif kind == _BOOL:
                out.append(int(v))
            else:
                out.extend(v if kind == _ARRAY else map(int, v))
                if len(v) < width:
                    out.extend([""] * (width - len(v)))
        return out


def _field_values(m: Any) -> Iterable[Any] | None:
    if m.msg is not None:
        return msgspec.structs.astuple(m.msg)
    if m.fields is not None:
        return m.fields.values()
    return None


def export_csv(
    reader: RecordingReader,
    out_dir: str | Path,
    *,
    topics: Iterable[str] | None = None,
    progress: Callable[[int], None] | None = None,
) -> CsvExport:
    """Write one CSV per selected topic instance into ``out_dir`` (created if needed).

    ``progress(n)`` is called with the number of messages handled since its previous call.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    selection = TopicSelection(topics or ())
    result = CsvExport()
    layouts: dict[tuple[str, int, int], _Layout] = {}
    names: dict[tuple[str, int, int], str] = {}
    for c in sorted(reader.channels(), key=lambda c: (c.topic, c.instance, c.id)):
        if (c.topic, c.instance) not in selection:
            continue
        if not c.decodable and not c.schema:
            why = f" ({c.raw_reason})" if c.raw_reason else ""
            result.notes.append(
                f"{c.topic}/{c.instance}: {c.message_count} messages from publisher {c.publisher_id:08x} were recorded "
                f"undecoded{why} and are not exported"
            )
            continue
        key = _table_key(c)
        if key not in layouts:
            layouts[key] = _Layout.from_schema(c.schema)
            taken = sum(1 for k in names if k[:2] == key[:2])
            suffix = f"_{c.fingerprint:016x}" if taken else ""
            names[key] = f"{c.topic}_{c.instance}{suffix}.csv"
    if any(layout.variable for layout in layouts.values()):
        _measure_variable_arrays(reader, layouts)
    files: dict[tuple[str, int, int], tuple[IO[str], Any, CsvTable]] = {}
    pending = 0
    try:
        for key, layout in layouts.items():
            path = out / names[key]
            handle = path.open("w", newline="")
            table = CsvTable(path, key[0], key[1], layout.columns())
            writer = csv.writer(handle)
            writer.writerow(table.columns)
            files[key] = (handle, writer, table)
            result.tables.append(table)
        for m in reader.iter_messages(selection):
            entry = files.get((m.topic, m.instance, m.fingerprint))
            values = _field_values(m)
            if entry is not None and values is not None:
                _, writer, table = entry
                row = [m.log_time_us, m.pub_time_us, f"{m.publisher_id:08x}", m.index]
                row += layouts[(m.topic, m.instance, m.fingerprint)].row(values)
                writer.writerow(row)
                table.rows += 1
            pending += 1
            if progress is not None and pending >= PROGRESS_EVERY:
                progress(pending)
                pending = 0
    finally:
        for handle, _, _ in files.values():
            handle.close()
    if progress is not None and pending:
        progress(pending)
    return result


def _table_key(c: ChannelInfo) -> tuple[str, int, int]:
    return (c.topic, c.instance, c.fingerprint)


def _measure_variable_arrays(reader: RecordingReader, layouts: dict[tuple[str, int, int], _Layout]) -> None:
    """A first pass over the topics with variable-length arrays, to size their columns."""
    wanted = {key: layout.variable for key, layout in layouts.items() if layout.variable}
    for m in reader.iter_messages(TopicSelection(f"{t}/{i}" for t, i, _ in wanted)):
        indexes = wanted.get((m.topic, m.instance, m.fingerprint))
        values = _field_values(m)
        if indexes is None or values is None:
            continue
        values = list(values)
        layout = layouts[(m.topic, m.instance, m.fingerprint)]
        for i in indexes:
            layout.widen(i, len(values[i]))
