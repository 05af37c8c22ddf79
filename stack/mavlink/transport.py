"""Byte transports under a MAVLink link: serial, UDP and TCP, all non-blocking.

``read()`` returns whatever is available (``b""`` when nothing is) and raises ``OSError`` when the transport is
dead (a serial device unplugged, a TCP connection closed). ``write()`` never blocks: on a stream (serial, TCP) the
bytes the kernel cannot take now wait in a bounded backlog flushed by later calls, so a frame is sent whole or not
at all; it returns False when the bytes were dropped (no peer yet, or the backlog is full).
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
from collections.abc import Callable
from typing import Protocol

import serial

from stack.mavlink.endpoint import Endpoint

READ_CHUNK = 65536
MAX_BACKLOG = 16384  # bytes waiting for a slow stream: ~0.18 s of a 921600-baud UART
TCP_CONNECT_TIMEOUT_S = 1.0


class Transport(Protocol):
    def fileno(self) -> int | None: ...
    def read(self) -> bytes: ...
    def write(self, data: bytes) -> bool: ...
    def close(self) -> None: ...


def open_transport(endpoint: Endpoint) -> Transport:
    """Open the endpoint; raises OSError (serial.SerialException is one) when it cannot be opened now."""
    if endpoint.kind == "serial":
        return SerialTransport(endpoint.device, endpoint.baud)
    if endpoint.kind == "udpin":
        return UdpInTransport(endpoint.host, endpoint.port)
    if endpoint.kind == "udpout":
        return UdpOutTransport(endpoint.host, endpoint.port)
    if endpoint.kind == "tcp":
        return TcpClientTransport(endpoint.host, endpoint.port)
    if endpoint.kind == "tcpin":
        return TcpServerTransport(endpoint.host, endpoint.port)
    raise ValueError(f"unknown endpoint kind {endpoint.kind!r}")


class _StreamWriter:
    """Whole-frame writes onto a non-blocking byte stream, with a bounded backlog."""

    def __init__(self) -> None:
        self.backlog = bytearray()

    def write(self, fd_write: Callable[[bytearray], int], data: bytes) -> bool:
        if self.backlog:
            self.flush(fd_write)
        if len(self.backlog) + len(data) > MAX_BACKLOG:
            return False
        self.backlog += data
        self.flush(fd_write)
        return True

    def flush(self, fd_write: Callable[[bytearray], int]) -> None:
        while self.backlog:
            try:
                sent = fd_write(self.backlog)
            except BlockingIOError:
                return
            if not sent:
                return
            del self.backlog[:sent]


class SerialTransport:
    """A serial device opened with pyserial (any baud, raw mode), then read and written on its fd directly."""

    def __init__(self, device: str, baud: int) -> None:
        # exclusive: a second process reading the same UART would steal half the bytes of every frame
        self.port = serial.Serial(device, baud, timeout=0, write_timeout=0, exclusive=True)
        os.set_blocking(self.port.fd, False)
        self.writer = _StreamWriter()

    def fileno(self) -> int | None:
        return self.port.fd

    def read(self) -> bytes:
        # pyserial's raw mode (VMIN = 0) makes an idle tty read as empty too: only empty after readiness is a hang-up
        if not select.select([self.port.fd], [], [], 0)[0]:
            return b""
        try:
            data = os.read(self.port.fd, READ_CHUNK)
        except BlockingIOError:
            return b""
        if not data:
            raise ConnectionError("serial device disconnected")
        return data

    def write(self, data: bytes) -> bool:
        return self.writer.write(lambda b: os.write(self.port.fd, b), data)

    def close(self) -> None:
        self.port.close()


class UdpInTransport:
    """Listens on HOST:PORT and sends to whoever sent the last datagram (as PX4 and pymavlink's udpin do)."""

    def __init__(self, host: str, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.sock.bind((host, port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)
        self.peer_address: tuple[str, int] | None = None

    def fileno(self) -> int | None:
        return self.sock.fileno()

    def read(self) -> bytes:
        chunks = []
        while True:
            try:
                data, self.peer_address = self.sock.recvfrom(READ_CHUNK)
            except (BlockingIOError, ConnectionRefusedError):
                return b"".join(chunks)
            chunks.append(data)

    def write(self, data: bytes) -> bool:
        if self.peer_address is None:
            return False
        try:
            self.sock.sendto(data, self.peer_address)
        except OSError:
            return False
        return True

    def close(self) -> None:
        self.sock.close()


class UdpPeerTransport:
    """Binds HOST:PORT and sends to whoever sent the last datagram, or to ``remote`` until someone has (PX4's
    ``mavlink start -u PORT -o REMOTE_PORT``: a vehicle that a ground station listening on the remote port hears
    at once). No SO_REUSEADDR: a second process must not share the port, each would get half the datagrams."""

    def __init__(self, host: str, port: int, remote: tuple[str, int] | None = None) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((host, port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)
        self.peer_address: tuple[str, int] | None = remote

    def fileno(self) -> int | None:
        return self.sock.fileno()

    def read(self) -> bytes:
        chunks = []
        while True:
            try:
                data, self.peer_address = self.sock.recvfrom(READ_CHUNK)
            except (BlockingIOError, ConnectionRefusedError):
                return b"".join(chunks)
            chunks.append(data)

    def write(self, data: bytes) -> bool:
        if self.peer_address is None:
            return False
        try:
            self.sock.sendto(data, self.peer_address)
        except OSError:
            return False
        return True

    def close(self) -> None:
        self.sock.close()


class UdpOutTransport:
    """Sends to HOST:PORT; connecting the socket binds it to the local address that reaches HOST, and only
    HOST:PORT's datagrams are received."""

    def __init__(self, host: str, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.connect((host, port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)

    def fileno(self) -> int | None:
        return self.sock.fileno()

    def read(self) -> bytes:
        chunks = []
        while True:
            try:
                chunks.append(self.sock.recv(READ_CHUNK))
            except (BlockingIOError, ConnectionRefusedError):  # refused: nobody listens there yet
                return b"".join(chunks)

    def write(self, data: bytes) -> bool:
        try:
            self.sock.send(data)
        except OSError:
            return False
        return True

    def close(self) -> None:
        self.sock.close()


class TcpClientTransport:
    def __init__(self, host: str, port: int) -> None:
        self.sock = socket.create_connection((host, port), timeout=TCP_CONNECT_TIMEOUT_S)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock.setblocking(False)
        self.writer = _StreamWriter()

    def fileno(self) -> int | None:
        return self.sock.fileno()

    def read(self) -> bytes:
        return _read_stream(self.sock)

    def write(self, data: bytes) -> bool:
        return self.writer.write(self.sock.send, data)

    def close(self) -> None:
        self.sock.close()


class TcpServerTransport:
    """Accepts one client at a time; a client that leaves is replaced by the next one to connect."""

    def __init__(self, host: str, port: int) -> None:
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.listener.bind((host, port))
            self.listener.listen(1)
        except OSError:
            self.listener.close()
            raise
        self.listener.setblocking(False)
        self.client: socket.socket | None = None
        self.writer = _StreamWriter()

    def fileno(self) -> int | None:
        return (self.client or self.listener).fileno()

    def read(self) -> bytes:
        if self.client is None:
            self._accept()
        if self.client is None:
            return b""
        try:
            return _read_stream(self.client)
        except OSError:
            self._drop_client()
            return b""

    def write(self, data: bytes) -> bool:
        if self.client is None:
            return False
        try:
            return self.writer.write(self.client.send, data)
        except OSError:
            self._drop_client()
            return False

    def close(self) -> None:
        self._drop_client()
        self.listener.close()

    def _accept(self) -> None:
        try:
            client, _ = self.listener.accept()
        except BlockingIOError:
            return
        client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        client.setblocking(False)
        self.client = client

    def _drop_client(self) -> None:
        if self.client is not None:
            with contextlib.suppress(OSError):
                self.client.close()
        self.client = None
        self.writer = _StreamWriter()


def _read_stream(sock: socket.socket) -> bytes:
    chunks = []
    while True:
        try:
            data = sock.recv(READ_CHUNK)
        except BlockingIOError:
            return b"".join(chunks)
        if not data:
            if chunks:  # hand over what came before the close; the next read reports it
                return b"".join(chunks)
            raise ConnectionError("connection closed by peer")
        chunks.append(data)
