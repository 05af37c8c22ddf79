"""Zenoh queries with JSON payloads: ask every queryable on a key and collect their JSON replies."""

from __future__ import annotations

import json

import zenoh


def query_json(session: zenoh.Session, key: str, payload: dict | None = None, timeout: float = 2.0) -> list[dict]:
    """The JSON replies of every queryable matching ``key`` (as many as answer within ``timeout`` seconds)."""
    replies = session.get(
        key,
        payload=json.dumps(payload) if payload is not None else None,
        consolidation=zenoh.ConsolidationMode.NONE,
        target=zenoh.QueryTarget.ALL,
        timeout=timeout,
    )
    out = []
    for reply in replies:
        if reply.ok is not None:
            out.append(json.loads(reply.ok.payload.to_string()))
    return out
