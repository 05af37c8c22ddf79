"""Zenoh queries with JSON payloads: ask every queryable on a key and collect their JSON replies; answer one."""

from __future__ import annotations

import json

import zenoh


def query_json(session: zenoh.Session, key: str, payload: dict | None = None, timeout: float = 2.0) -> list[dict]:
    """The JSON replies of every queryable matching ``key`` (as many as answer within ``timeout`` seconds); a reply
    that is not JSON is dropped."""
    replies = session.get(
        key,
        payload=json.dumps(payload) if payload is not None else None,
        consolidation=zenoh.ConsolidationMode.NONE,
        target=zenoh.QueryTarget.ALL,
        timeout=timeout,
    )
    out = []
    for reply in replies:
        if reply.ok is None:
            continue
        try:
            out.append(json.loads(reply.ok.payload.to_string()))
        except ValueError:
            continue
    return out


def answer(query: zenoh.Query, key: str, payload: str) -> None:
    """Reply to ``query``, never waiting for room on the way: Zenoh's replies block by default, and a reply to a
    tool behind a slow link would hold up every router it passes (a dropped one is a query that times out)."""
    query.reply(key, payload, congestion_control=zenoh.CongestionControl.DROP)
