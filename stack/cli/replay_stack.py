"""The bus of ``stack replay``: a recording republished on a bus of its own, as a stack beside any other.

A replay never joins a running stack: replayed and live messages would mix on one bus, and a lockstep
stack would meet the recording's lockstep times beside its own. Like each ``stack fly``, it is a stack of
its own: a Zenoh router on a free 127.0.0.1 port (no scouting, explicit endpoints), registered in the run
state as ``<vehicle>-replay-<pid>`` (:mod:`stack.supervisor.state`), answering ``stack status`` with no
modules. ``stack topic``, ``stack plot`` and scripts attach to it with ``--vehicle <vehicle>-replay-<pid>``,
or with no name when no other stack runs; the topic keys are the recorded vehicle's.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig
from stack.bus.node import Node
from stack.bus.ports import free_port, port_taken
from stack.bus.query import answer
from stack.bus.supervisors import SINGLE_HOST
from stack.supervisor import state as run_state

ROUTER_PORT_ATTEMPTS = 5


class ReplayStack:
    """The replay's own bus: a router on a free loopback port, registered as a stack while it is open."""

    def __init__(self, vehicle: str, lockstep: bool, source: Path) -> None:
        self.vehicle = vehicle
        self.lockstep = lockstep
        self.source = source
        self.name = run_state.replay_name(vehicle, os.getpid())
        self.node = self._open()
        self._status_key = keys.supervisor_key(vehicle, SINGLE_HOST, "status")
        self._status = self.node.session.declare_queryable(self._status_key, self._on_status)
        client = BusConfig(mode="client", connect=(self.endpoint,), listen=())
        run_state.write_state(
            vehicle,
            {
                **run_state.process_identity(),
                "kind": run_state.REPLAY,
                "vehicle": vehicle,
                "profile": str(source.resolve()),
                "endpoint": self.endpoint,
                "bus": json.loads(client.to_json()),
                "lockstep": lockstep,
                "started": time.time(),
            },
        )

    def _open(self) -> Node:
        for attempt in range(ROUTER_PORT_ATTEMPTS):
            self.endpoint = f"tcp/127.0.0.1:{free_port()}"
            try:
                return Node(BusConfig(mode="router", listen=(self.endpoint,)), self.vehicle, "replay", stable_id=False)
            except zenoh.ZError as e:
                if attempt + 1 == ROUTER_PORT_ATTEMPTS or not port_taken(e):
                    raise
        raise AssertionError("unreachable")

    def _on_status(self, query: zenoh.Query) -> None:
        report = {
            "vehicle": self.vehicle,
            "host": SINGLE_HOST,
            "profile": f"replay of {self.source.name}",
            "lockstep": self.lockstep,
        }
        answer(query, self._status_key, json.dumps({**report, "modules": []}))

    def __enter__(self) -> ReplayStack:
        return self

    def __exit__(self, *exc: object) -> None:
        run_state.remove_state(self.vehicle, os.getpid())
        self._status.undeclare()
        self.node.close()
