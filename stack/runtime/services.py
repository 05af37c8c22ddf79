"""Per-module services that run beside the loop: the parameter service and the heartbeat."""

from __future__ import annotations

import json
import logging
import os
import socket
import threading
from collections.abc import Callable

import msgspec
import psutil
import zenoh

from stack.bus import keys
from stack.bus.query import answer
from stack.bus.topics import MAX_SAMPLE_BYTES
from stack.msg.internal import ModuleHeartbeat
from stack.params.param import ParamError
from stack.params.store import ParamStore

log = logging.getLogger("stack.runtime")

LIST_REPLY_BYTES = MAX_SAMPLE_BYTES // 2
"""The most parameter descriptions [bytes of JSON] one reply lists: a reply larger than the bus carries is lost
without a word, so a module with many parameters (the simulator's takeover reads every loop's) lists them in
several replies."""


class ParamService:
    """Answers parameter queries for one module (:mod:`stack.params.client`), on Zenoh's callback thread.

    Query payload: JSON ``{"op": "list"|"get"|"check"|"set", "name": ..., "value": ...}``; the reply is JSON,
    with an ``error`` member when a request is refused (nothing changes then). ``check`` validates a value
    as ``set`` would and changes nothing, so a client can set a parameter in every module that has it or
    in none.
    """

    def __init__(self, session: zenoh.Session, vehicle: str, module: str, store: ParamStore) -> None:
        self.module = module
        self.store = store
        self.key = keys.param_key(vehicle, module)
        self._queryable = session.declare_queryable(self.key, self._on_query)

    def _on_query(self, query: zenoh.Query) -> None:
        try:
            request = json.loads(query.payload.to_string()) if query.payload is not None else {"op": "list"}
            replies = self.replies(self.handle(request))
        except (ValueError, TypeError, AttributeError) as e:
            replies = [json.dumps({"module": self.module, "error": f"bad request: {e}"})]
        for reply in replies:
            answer(query, self.key, reply)

    def replies(self, result: dict[str, object]) -> list[str]:
        """The JSON replies of an answer: one, or for a list as many as it takes to keep each to LIST_REPLY_BYTES
        (the client joins a module's pieces)."""
        params = result.get("params")
        if not isinstance(params, list):
            return [json.dumps(result)]
        pieces: list[list[object]] = [[]]
        size = 0
        for p in params:
            length = len(json.dumps(p)) + 2
            if pieces[-1] and size + length > LIST_REPLY_BYTES:
                pieces.append([])
                size = 0
            pieces[-1].append(p)
            size += length
        return [json.dumps({"module": self.module, "params": piece}) for piece in pieces]

    def handle(self, request: dict[str, object]) -> dict[str, object]:
        op = request.get("op", "list")
        values = self.store.values()
        if op == "list":
            params = [{**p.describe(), "value": values[p.name]} for p in self.store.defs.values()]
            return {"module": self.module, "params": params}
        name = str(request.get("name", ""))
        try:
            if op == "get":
                self.store.definition(name)
                return {"module": self.module, "name": name, "value": values[name]}
            if op == "check":
                value = self.store.definition(name).check(request.get("value"))
                return {"module": self.module, "name": name, "value": value}
            if op == "set":
                old, new = self.store.set(name, request.get("value"))
                return {"module": self.module, "name": name, "old": old, "new": new}
        except ParamError as e:
            return {"module": self.module, "name": name, "error": str(e)}
        return {"module": self.module, "error": f"unknown op '{op}'"}

    def close(self) -> None:
        self._queryable.undeclare()


class Heartbeat:
    """Publishes the module's presence and counters about once a second (wall time)."""

    def __init__(self, session: zenoh.Session, vehicle: str, module: str, snapshot: Callable[[], dict]) -> None:
        self._pub = session.declare_publisher(keys.heartbeat_key(vehicle, module))
        self._snapshot = snapshot
        self._module = module
        self._process = psutil.Process()
        self._process.cpu_percent(None)
        self._host = socket.gethostname()
        self._encoder = msgspec.msgpack.Encoder()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="heartbeat", daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        while not self._stop.wait(1.0):
            self.beat()

    def beat(self) -> None:
        try:
            with self._process.oneshot():
                cpu = self._process.cpu_percent(None)
                rss = self._process.memory_info().rss
            status = self._snapshot()
            hb = ModuleHeartbeat(
                module=self._module, pid=os.getpid(), host=self._host, cpu_percent=cpu, rss_bytes=rss, **status
            )
            self._pub.put(self._encoder.encode(hb))
        except zenoh.ZError:
            pass  # the session is closing

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._pub.undeclare()
