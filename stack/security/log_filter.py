"""The filter a router's standard output passes through (stack.security.denials), run as its own process.

Zenoh's access-control lines (one per message the router handles, at TRACE level) are kept from the output: those
telling of a denial go to the standard error (a pipe the router's process reads), the others nowhere; every other
line goes on to the standard output as it came. It reads what is there, in blocks, and writes each block's lines at
once: a line-at-a-time reader (``sed -u`` reads a byte per system call, 19 µs of CPU a line) fell behind the router,
which then waited on its full pipe. Run by path, without the ``site`` module, so it starts in milliseconds.
"""

from __future__ import annotations

import contextlib
import os
import time

TARGET = b"zenoh::net::routing::interceptor::access_control"
DENIED = b" is unauthorized to "
BLOCK_BYTES = 1 << 16
GATHER_S = 0.005
"""How long it lets the lines gather once it has read all there was: woken for every line (one per message the
router passes), it cost the machine a context switch per message; 5 ms of the log fit in a pipe."""


def split(lines: list[bytes]) -> tuple[list[bytes], list[bytes]]:
    """(the lines to pass on, the denials) among ``lines``."""
    passed, denied = [], []
    for line in lines:
        if TARGET not in line:
            passed.append(line)
        elif DENIED in line:
            denied.append(line)
    return passed, denied


def _write(fd: int, lines: list[bytes]) -> None:
    data = memoryview(b"".join(line + b"\n" for line in lines))
    while data:
        data = data[os.write(fd, data) :]


def main() -> None:
    partial = b""
    while chunk := os.read(0, BLOCK_BYTES):
        *lines, partial = (partial + chunk).split(b"\n")
        passed, denied = split(lines)
        if passed:
            _write(1, passed)
        if denied:
            _write(2, denied)
        if len(chunk) < BLOCK_BYTES:
            time.sleep(GATHER_S)
    if partial:
        passed, denied = split([partial])
        _write(1, passed)
        _write(2, denied)


if __name__ == "__main__":
    with contextlib.suppress(BrokenPipeError, KeyboardInterrupt):
        main()
