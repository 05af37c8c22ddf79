"""A ground station for the tests, in pymavlink: it listens where the vehicle sends (as QGroundControl listens on
UDP 14550), keeps every message it receives, and sends its own HEARTBEAT at 1 Hz while asked to (signed, with a
key).

Also the stacks the tests run: the default profile with the links moved to free ports, plus extra links.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import signing
from stack.mavlink.framing import FrameParser
from tests.support.harness import REPO, udp_port, write_profile

VEHICLE = (1, 1)


class Peer:
    def __init__(self, port: int, system: int = 255, component: int = 190, key: bytes | None = None) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.sock.settimeout(0.05)
        self.mav = mavlink2.MAVLink(self, system, component)
        if key is not None:
            signing.enable(self.mav, key)
        self.parser = FrameParser(mavlink2.MAVLink(None, system, component))  # takes signed frames unchecked
        self.vehicle: tuple[str, int] | None = None
        self.received: list[tuple[float, Any]] = []
        self.heartbeats = True
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def write(self, data: bytes) -> None:
        if self.vehicle is not None:
            with contextlib.suppress(OSError):
                self.sock.sendto(data, self.vehicle)

    def send_raw(self, data: bytes) -> None:
        self.write(data)

    def _run(self) -> None:
        next_heartbeat = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if self.heartbeats and now >= next_heartbeat and self.vehicle is not None:
                next_heartbeat = now + 1.0
                self.mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            try:
                data, address = self.sock.recvfrom(65536)
            except (TimeoutError, OSError):
                continue
            self.vehicle = address
            messages = self.parser.feed(data)
            with self._cond:
                self.received.extend((time.monotonic(), m) for m in messages)
                self._cond.notify_all()

    def mark(self) -> int:
        """A point in the received messages: ``wait(..., after=mark)`` looks only at what came after it."""
        with self._cond:
            return len(self.received)

    def wait(
        self, kind: str, check: Callable[[Any], bool] = lambda m: True, timeout: float = 10.0, after: int = 0
    ) -> Any:
        deadline = time.monotonic() + timeout
        with self._cond:
            seen = after
            while True:
                for _, msg in self.received[seen:]:
                    if msg.get_type() == kind and check(msg):
                        return msg
                seen = len(self.received)
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"no {kind} within {timeout:g} s")
                self._cond.wait(min(left, 0.1))

    def all(self, kind: str, after: int = 0) -> list[Any]:
        with self._cond:
            return [m for _, m in self.received[after:] if m.get_type() == kind]

    def connect(self, timeout: float = 30.0) -> Any:
        return self.wait("HEARTBEAT", lambda m: (m.get_srcSystem(), m.get_srcComponent()) == VEHICLE, timeout)

    def command(self, command: int, *params: float, timeout: float = 10.0) -> Any:
        """COMMAND_LONG to the autopilot; its COMMAND_ACK."""
        mark = self.mark()
        p = [*params, *[0.0] * (7 - len(params))]
        self.mav.command_long_send(*VEHICLE, command, 0, *p)
        return self.wait("COMMAND_ACK", lambda m: m.command == command, timeout, mark)

    def mode(self, timeout: float = 10.0) -> int:
        """The custom_mode of the next vehicle HEARTBEAT."""
        mark = self.mark()
        return self.wait("HEARTBEAT", lambda m: m.get_srcSystem() == VEHICLE[0], timeout, mark).custom_mode

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.sock.close()


@dataclass
class Link:
    name: str
    local: int
    remote: int
    extra: str = ""

    def toml(self) -> str:
        args = f'device = "udp:127.0.0.1:{self.local}", remote = "127.0.0.1:{self.remote}"{self.extra}'
        return f'[[module]]\nname = "{self.name}"\nmodule = "mavlink"\nargs = {{ {args} }}\n'


def links_profile(path: Path, links: list[Link], stack: str = "") -> Path:
    """The default profile with these links (the default ones, mavlink_gcs and mavlink_api, moved to free ports
    when not given); ``stack`` is added to its [stack] table."""
    names = {link.name for link in links}
    links = links + [Link(n, udp_port(), udp_port()) for n in ("mavlink_gcs", "mavlink_api") if n not in names]
    text = f'extends = "{REPO / "launch" / "sitl_quad.toml"}"\n'
    if stack:
        text += f"[stack]\n{stack}\n"
    return write_profile(path, text + "\n".join(link.toml() for link in links))
