"""The simulated Pixhawk's physical link: a UDP socket or a UART on a pseudo-terminal, with faults, below MAVLink.

The MAVLink link layer (``stack.mavlink.link.MavlinkLink``) opens its transport from an endpoint string, so the
simulated Pixhawk gives it ``udpout:127.0.0.1:PORT`` of a loopback socket that :class:`Wire` owns; every frame
the link sends arrives there as one datagram, goes through the :class:`~stack.pixhawk_sim.faults.FaultInjector`
and out on the real link, and what comes in on the real link goes the other way. The real links:

* UDP: ``udpout:HOST:PORT`` (send to the companion, as PX4 SITL sends to 14540) or ``udpin:HOST:PORT`` (listen,
  answer whoever spoke last), with the link layer's own UDP transports;
* :class:`PtyUart`: a pseudo-terminal pair whose slave the companion opens as a serial device
  (``serial:PATH:921600``), paced in both directions to the UART's byte rate by
  :class:`~stack.pixhawk_sim.uart.UartPacer`.
"""

from __future__ import annotations

import contextlib
import os
import socket
import tty
from pathlib import Path
from typing import Protocol

from stack.mavlink.endpoint import DEFAULT_BAUD, parse_endpoint
from stack.mavlink.transport import READ_CHUNK, UdpInTransport, UdpOutTransport
from stack.pixhawk_sim.faults import FaultInjector
from stack.pixhawk_sim.uart import RX_BUFFER_BYTES, UartPacer

LOOPBACK = "127.0.0.1"
SERVICE_PERIOD_S = 0.001
"""How often a paced pty moves bytes: ~92 bytes a time at 921600 baud."""
READER_BACKLOG_BYTES = 65536
"""Bytes that left the UART but the companion has not read yet (a Linux serial driver's buffering)."""


class PhysicalLink(Protocol):
    def fileno(self) -> int | None: ...
    def read(self, now_s: float) -> bytes: ...
    def write(self, data: bytes, now_s: float) -> bool: ...
    def pump(self, now_s: float) -> None: ...
    def next_event_s(self, now_s: float) -> float | None: ...
    def describe(self) -> dict[str, object]: ...
    def close(self) -> None: ...


class UdpLink:
    """A UDP endpoint (``udpin:`` or ``udpout:``); packets travel whole and at once."""

    def __init__(self, endpoint: str) -> None:
        ep = parse_endpoint(endpoint)
        if ep.kind == "udpin":
            self.transport: UdpInTransport | UdpOutTransport = UdpInTransport(ep.host, ep.port)
        elif ep.kind == "udpout":
            self.transport = UdpOutTransport(ep.host, ep.port)
        else:
            raise ValueError(f"{endpoint!r}: the simulated Pixhawk's UDP link is udpin:HOST:PORT or udpout:HOST:PORT")
        self.endpoint = str(ep)
        self.send_failures = 0

    def fileno(self) -> int | None:
        return self.transport.fileno()

    def read(self, now_s: float) -> bytes:
        return self.transport.read()

    def write(self, data: bytes, now_s: float) -> bool:
        sent = self.transport.write(data)
        if not sent:
            self.send_failures += 1
        return sent

    def pump(self, now_s: float) -> None:
        """Nothing waits on a datagram link."""

    def next_event_s(self, now_s: float) -> float | None:
        return None

    def describe(self) -> dict[str, object]:
        return {"endpoint": self.endpoint, "send_failures": self.send_failures}

    def close(self) -> None:
        self.transport.close()


class PtyUart:
    """A pseudo-terminal pair: this side holds the master, the companion opens the slave (``path``, and the
    symlink ``link_path`` when given). Both directions run at the UART's byte rate, moved every
    :data:`SERVICE_PERIOD_S` at most (a UART's DMA moves bytes in blocks too). The slave stays open here too, so
    the companion may close and reopen it. A pty holds only ~4 KB for its reader, where a serial port's driver
    buffers far more, so the bytes it cannot take yet wait here, up to :data:`READER_BACKLOG_BYTES`; beyond that
    (nobody reading) they are lost and counted (``unread_drops``), as on a UART with nothing connected."""

    def __init__(self, baud: int = DEFAULT_BAUD, link_path: Path | None = None) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self.baud = baud
        self.tx = UartPacer(baud)
        self.rx = UartPacer(baud, RX_BUFFER_BYTES)
        self.unread_drops = 0
        self._backlog = bytearray()
        self.link_path = link_path
        if link_path is not None:
            with contextlib.suppress(FileNotFoundError):
                if link_path.is_symlink():
                    link_path.unlink()
            link_path.symlink_to(self.path)

    def fileno(self) -> int | None:
        return self.master

    def read(self, now_s: float) -> bytes:
        while True:
            try:
                data = os.read(self.master, READ_CHUNK)
            except OSError:  # nothing to read (EAGAIN)
                break
            if not data:
                break
            self.rx.offer_bytes(data, now_s)
        return self.rx.take(now_s)

    def write(self, data: bytes, now_s: float) -> bool:
        return self.tx.offer(data, now_s)

    def pump(self, now_s: float) -> None:
        backlog = self._backlog
        backlog += self.tx.take(now_s)
        while backlog:
            try:
                written = os.write(self.master, backlog)
            except BlockingIOError:
                break
            del backlog[:written]
        excess = len(backlog) - READER_BACKLOG_BYTES
        if excess > 0:
            del backlog[:excess]
            self.unread_drops += excess

    def next_event_s(self, now_s: float) -> float | None:
        if not (self.tx.queued or self.rx.queued):
            return None  # a backlog waiting for the reader is retried at the next step
        return now_s + SERVICE_PERIOD_S

    def describe(self) -> dict[str, object]:
        return {
            "pty": self.path,
            "link": str(self.link_path) if self.link_path is not None else None,
            "baud": self.baud,
            "tx": {**vars(self.tx.counters), "queued": self.tx.queued},
            "rx": {**vars(self.rx.counters), "queued": self.rx.queued},
            "unread_backlog": len(self._backlog),
            "unread_drops": self.unread_drops,
        }

    def close(self) -> None:
        if self.link_path is not None:
            with contextlib.suppress(OSError):
                if self.link_path.is_symlink() and os.readlink(self.link_path) == self.path:
                    self.link_path.unlink()
        for fd in (self.master, self.slave):
            with contextlib.suppress(OSError):
                os.close(fd)


class Wire:
    """The loopback hop to the MAVLink link layer, the faults, and the physical link (see the module docstring)."""

    def __init__(self, physical: PhysicalLink, faults: FaultInjector) -> None:
        self.physical = physical
        self.faults = faults
        self.inner = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.inner.bind((LOOPBACK, 0))
        self.inner.setblocking(False)
        self._link_address: tuple[str, int] | None = None

    @property
    def link_endpoint(self) -> str:
        """The endpoint the MAVLink link layer opens to reach this wire."""
        host, port = self.inner.getsockname()
        return f"udpout:{host}:{port}"

    def fds(self) -> list[int]:
        fds = [self.inner.fileno()]
        fd = self.physical.fileno()
        if fd is not None:
            fds.append(fd)
        return fds

    def service(self, now_s: float) -> None:
        """Move what is due: frames from the link layer out, bytes from the physical link in."""
        faults = self.faults
        while True:
            try:
                frame, self._link_address = self.inner.recvfrom(READ_CHUNK)
            except BlockingIOError:
                break
            faults.send(frame, now_s)
        for data in faults.outbound.pop_due(now_s):
            self.physical.write(data, now_s)
        self.physical.pump(now_s)
        received = self.physical.read(now_s)
        if received:
            faults.receive(received, now_s)
        if self._link_address is not None:
            for data in faults.inbound.pop_due(now_s):
                with contextlib.suppress(OSError):
                    self.inner.sendto(data, self._link_address)

    def next_event_s(self, now_s: float) -> float | None:
        times = [t for t in (self.faults.next_due(), self.physical.next_event_s(now_s)) if t is not None]
        return min(times) if times else None

    def close(self) -> None:
        self.inner.close()
        self.physical.close()
