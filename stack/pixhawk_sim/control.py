"""The simulated Pixhawk's control channel: JSON datagrams on a 127.0.0.1 UDP port, for tests and scenarios.

A request is one JSON object; every request is answered with one, sent back to its sender:

* ``{"cut_s": 2}`` cuts the link (both directions) for 2 s from now;
* ``{"drop": 0.05}``, ``{"corrupt": 1e-4}``, ``{"latency_ms": 20, "jitter_ms": 5}`` change the faults (any
  combination; all or nothing);
* ``{"status": true}`` (or any request) answers with the state: mode, armed, failsafe, boot time, the faults and
  their counters, the link counters.

The answer is ``{"ok": true, ...}`` or ``{"ok": false, "error": "..."}``.
"""

from __future__ import annotations

import contextlib
import json
import socket
from collections.abc import Callable

from stack.pixhawk_sim.faults import FaultInjector

CUT_KEY = "cut_s"
STATUS_KEY = "status"
MAX_DATAGRAM = 65536


def apply_request(request: object, faults: FaultInjector, now_s: float) -> dict[str, object]:
    """Apply one decoded request; the answer without the state (see the module docstring)."""
    if not isinstance(request, dict):
        return {"ok": False, "error": "a request is a JSON object"}
    changes = {k: v for k, v in request.items() if k not in (CUT_KEY, STATUS_KEY)}
    try:
        for key, value in changes.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{key} must be a number, got {value!r}")
        cut = request.get(CUT_KEY)
        if cut is not None and (isinstance(cut, bool) or not isinstance(cut, int | float) or cut < 0):
            raise ValueError(f"{CUT_KEY} must be a number ≥ 0, got {cut!r}")
        faults.configure(**changes)
        if cut is not None:
            faults.cut(now_s, float(cut))
    except ValueError as e:
        return {"ok": False, "error": str(e)}
    return {"ok": True}


class ControlChannel:
    """The UDP socket; ``service`` answers every waiting request with ``apply_request`` plus ``status()``."""

    def __init__(self, port: int, faults: FaultInjector, status: Callable[[], dict[str, object]]) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind(("127.0.0.1", port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)
        self.port = self.sock.getsockname()[1]
        self.faults = faults
        self.status = status

    def fileno(self) -> int:
        return self.sock.fileno()

    def service(self, now_s: float) -> None:
        while True:
            try:
                data, sender = self.sock.recvfrom(MAX_DATAGRAM)
            except BlockingIOError:
                return
            try:
                request = json.loads(data)
            except (json.JSONDecodeError, UnicodeDecodeError) as e:
                answer: dict[str, object] = {"ok": False, "error": f"not JSON: {e}"}
            else:
                answer = apply_request(request, self.faults, now_s)
            answer.update(self.status())
            with contextlib.suppress(OSError):
                self.sock.sendto(json.dumps(answer).encode(), sender)

    def close(self) -> None:
        self.sock.close()
