"""Reading .rrd files back with Rerun's own reader, for assertions on entities, timelines and rows."""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pyarrow as pa
from rerun.chunk import RrdReader


@dataclass
class RrdContent:
    recordings: list[Any]
    blueprints: list[Any]
    # entity → [(sim_time µs, {component column: value})], sorted by time
    temporal: dict[str, list[tuple[int, dict[str, Any]]]] = field(default_factory=dict)
    # entity → {component column: value} of its static data
    static: dict[str, dict[str, Any]] = field(default_factory=dict)
    timelines: dict[str, set[str]] = field(default_factory=dict)
    # entity → {component column: (archetype, component type)} from the Arrow field metadata
    kinds: dict[str, dict[str, tuple[str, str]]] = field(default_factory=dict)

    def rows(self, entity: str) -> int:
        return len(self.temporal.get(entity, []))

    def times(self, entity: str) -> list[int]:
        return [t for t, _ in self.temporal.get(entity, [])]

    def values(self, entity: str, column: str = "Scalars:scalars") -> list[Any]:
        return [row[column] for _, row in self.temporal.get(entity, [])]

    def entities(self) -> set[str]:
        return set(self.temporal)


def read_rrd(path: str | Path) -> RrdContent:
    reader = RrdReader(str(path))
    content = RrdContent(recordings=reader.recordings(), blueprints=reader.blueprints())
    temporal: dict[str, list[tuple[int, dict[str, Any]]]] = defaultdict(list)
    timelines: dict[str, set[str]] = defaultdict(set)
    for chunk in reader.stream().to_chunks():
        batch = chunk.to_record_batch()
        components = [n for n in batch.schema.names if ":" in n]
        for f in batch.schema:
            if f.name in components:
                meta = f.metadata or {}
                kind = (meta.get(b"rerun:archetype", b"").decode(), meta.get(b"rerun:component_type", b"").decode())
                content.kinds.setdefault(chunk.entity_path, {})[f.name] = kind
        if not chunk.timeline_names:
            content.static.setdefault(chunk.entity_path, {}).update(
                {n: batch.column(n).to_pylist()[0] for n in components}
            )
            continue
        timelines[chunk.entity_path].update(chunk.timeline_names)
        if "sim_time" not in chunk.timeline_names:
            continue
        times = batch.column("sim_time").cast(pa.int64()).to_pylist()
        columns = {n: batch.column(n).to_pylist() for n in components}
        for i, t in enumerate(times):
            temporal[chunk.entity_path].append((t // 1000, {n: v[i] for n, v in columns.items()}))
    content.temporal = {k: sorted(v, key=lambda item: item[0]) for k, v in temporal.items()}
    content.timelines = dict(timelines)
    return content
