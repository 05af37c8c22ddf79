"""The bus of a swarm spread over machines (``stack fly SCENARIO --vehicles N --here ...``).

Each machine's launcher opens a router, the hub: its vehicles join it on 127.0.0.1, it listens where the others'
hubs reach it (``--listen``) or reaches theirs (``--join``), and it outlives the vehicles, so a vehicle that ends
(or is killed, as the leader of ``swarm_leader_loss`` is) takes no other vehicle's link with it. The launcher reads
every vehicle's result from it: the scenario module puts it on ``stack/<vehicle>/@scenario/result`` as it ends.

Over ``tls/`` endpoints the hubs link on mutual TLS as hosts of one keystore, each presenting the identity given
before the command (``stack --keystore DIR --identity NAME fly ...``), with the keystore's access rules
(stack.security.acl): the other hubs and this machine's vehicles may do everything, an operator or an observer what
its role allows, anyone else nothing.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig, open_router
from stack.bus.ports import free_port
from stack.cli.common import IDENTITY_ENV, KEYSTORE_ENV
from stack.security.denials import Denial, DenialCounts
from stack.security.keystore import KeystoreError

RESULTS_WAIT_S = 60.0
"""How long the results of the vehicles elsewhere are waited for once this machine's have ended, while those
vehicles are still on the bus."""


def hub_security(listen: Sequence[str], join: Sequence[str]) -> tuple[dict[str, str], dict[str, object]]:
    """What a hub presents and whom it lets in when it links over ``tls/`` (none over plain links); KeystoreError
    saying what is missing."""
    if not any(e.startswith("tls/") for e in (*listen, *join)):
        return {}, {}
    keystore, identity = os.environ.get(KEYSTORE_ENV, ""), os.environ.get(IDENTITY_ENV, "")
    if not keystore or not identity:
        raise KeystoreError(
            "a swarm's hub links over tls/ as a host of a keystore: give `stack --keystore DIR --identity NAME fly ...`"
        )
    from stack.security.acl import access_rules
    from stack.security.tls import tls_files

    root = Path(keystore).expanduser().resolve()
    return tls_files(root, identity, role="host"), access_rules(root)


class Hub:
    def __init__(
        self,
        listen: Sequence[str],
        join: Sequence[str],
        tls: dict[str, str],
        access: dict[str, object],
        count_denials: bool = True,
    ) -> None:
        self.local = f"tcp/127.0.0.1:{free_port()}"
        bus = BusConfig(
            mode="router", listen=(self.local, *listen), connect=tuple(join), low_latency=False, tls=tls, access=access
        )
        self.denied = DenialCounts()
        self.session = open_router(bus, "swarm-hub", len(join) + 1, self._on_denial if count_denials else None)
        self.results: dict[str, dict[str, Any]] = {}
        self._arrived = threading.Condition()
        self._results = self.session.declare_subscriber(keys.scenario_result_key("*"), self._on_result)

    def _on_denial(self, denial: Denial) -> None:
        if self.denied.add(denial, time.time()):
            print(f"[swarm] hub: {denial.describe()}", flush=True)

    def _on_result(self, sample: zenoh.Sample) -> None:
        vehicle = str(sample.key_expr).split("/")[1]
        try:
            result = json.loads(sample.payload.to_string())
        except ValueError:
            return
        if isinstance(result, dict):
            with self._arrived:
                self.results[vehicle] = result
                self._arrived.notify_all()

    def on_bus(self, vehicle: str) -> bool:
        return any(r.ok is not None for r in self.session.liveliness().get(keys.alive_query(vehicle), timeout=1.0))

    def wait_results(self, vehicles: Sequence[str]) -> None:
        """Until every vehicle's result has come, or one missing is no longer on the bus, or RESULTS_WAIT_S."""
        end = time.monotonic() + RESULTS_WAIT_S
        while time.monotonic() < end:
            missing = [v for v in vehicles if v not in self.results]
            if not missing or not any(self.on_bus(v) for v in missing):
                return
            with self._arrived:
                self._arrived.wait(1.0)

    def close(self) -> None:
        self._results.undeclare()
        self.session.close()
