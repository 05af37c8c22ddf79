"""`stack teleop` in a pseudo-terminal, as a person at a terminal runs it, and the sticks it puts on the bus."""

from __future__ import annotations

import fcntl
import json
import os
import re
import struct
import subprocess
import sys
import termios
import threading
import time
from collections.abc import Callable
from pathlib import Path

from tests.support.harness import REPO, stack_env

CONTROL = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
ROWS, COLUMNS = 40, 200
"""Wide enough for a device path under a test worker's temporary directory (the screen cuts longer lines)."""
REPEAT_S = 0.033
"""A terminal's auto-repeat interval (30 Hz)."""


def _controlling_terminal() -> None:
    """In the child, after setsid: the pty on stdin becomes its terminal, so Ctrl-C is SIGINT as at a desk."""
    fcntl.ioctl(0, termios.TIOCSCTTY, 0)


class Teleop:
    """`stack teleop ARGS` on the slave side of a pty; the test types on the master side and reads the screen."""

    def __init__(self, home: Path, *args: str) -> None:
        self.master, self.slave = os.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", ROWS, COLUMNS, 0, 0))
        self.attrs_before = termios.tcgetattr(self.slave)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "stack", "teleop", *args],
            stdin=self.slave,
            stdout=self.slave,
            stderr=self.slave,
            env=stack_env(home),
            cwd=REPO,
            start_new_session=True,
            preexec_fn=_controlling_terminal,
        )
        self._out = bytearray()
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            with self._lock:
                self._out.extend(data)

    @property
    def output(self) -> str:
        with self._lock:
            return self._out.decode(errors="replace")

    def screen(self) -> str:
        """The last whole screen drawn, without its control sequences."""
        with self._lock:
            end = self._out.rfind(b"\x1b[J")
            start = self._out.rfind(b"\x1b[H", 0, end)
            frame = bytes(self._out[start + 3 : end]) if start >= 0 else b""
        return CONTROL.sub("", frame.decode(errors="replace")).replace("\r\n", "\n")

    def wait_for(self, pattern: str, timeout: float = 30.0) -> re.Match[str]:
        regex = re.compile(pattern)
        deadline = time.monotonic() + timeout
        while True:
            if (m := regex.search(self.screen())) is not None:
                return m
            if time.monotonic() > deadline or self.proc.poll() is not None:
                shown = self.screen() if self.proc.poll() is None else self.output
                raise AssertionError(f"'{pattern}' not on the screen within {timeout:g} s:\n{shown}")
            time.sleep(0.05)

    def type(self, keys: str | bytes, times: int = 1, interval: float = REPEAT_S) -> None:
        data = keys.encode() if isinstance(keys, str) else keys
        for _ in range(times):
            os.write(self.master, data)
            time.sleep(interval)

    def hold(self, keys: str | bytes, seconds: float) -> None:
        """A key held down: one press, the auto-repeat delay, then presses every REPEAT_S."""
        self.type(keys, interval=0.5)
        self.type(keys, times=round((seconds - 0.5) / REPEAT_S))

    def holding(self, keys: str | bytes, pattern: str, timeout: float = 10.0) -> re.Match[str]:
        """A key held down until ``pattern`` is on the screen."""
        deadline = time.monotonic() + timeout
        while (m := re.search(pattern, self.screen())) is None:
            assert time.monotonic() < deadline, f"'{pattern}' not on the screen within {timeout:g} s:\n{self.screen()}"
            self.type(keys)
        return m

    def command(self, act: Callable[[], None], label: str, timeout: float = 10.0) -> str:
        """``act`` (a key, a button) and the vehicle's answer to the command it sends."""
        before = re.search(r"last command #(\d+)", self.screen())
        sent = int(before.group(1)) if before else 0
        act()
        return self.wait_for(rf"last command #{sent + 1}: {label}: (?!sent)(.*)", timeout).group(1)

    def until_accepted(self, act: Callable[[], None], label: str, timeout: float = 60.0) -> None:
        """``act`` until the vehicle accepts its command (the pre-arm checks may not pass at once, a landing not be
        detected yet)."""
        deadline = time.monotonic() + timeout
        while (answer := self.command(act, label)) != "accepted":
            assert time.monotonic() < deadline, f"{label}: {answer}\n{self.screen()}"
            time.sleep(1.0)

    def exit_code(self, timeout: float = 20.0) -> int:
        code = self.proc.wait(timeout)
        self._reader.join(2.0)
        return code

    def terminal_restored(self) -> bool:
        return termios.tcgetattr(self.slave) == self.attrs_before

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master)
        os.close(self.slave)


class SticksOnTheBus:
    """Every manual_control_setpoint on the bus, from `stack topic echo` (another process: this test's own does not
    open a Zenoh session, then fork)."""

    def __init__(self, home: Path) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "stack", "topic", "echo", "manual_control_setpoint", "--json", "--timeout", "600"],
            env=stack_env(home),
            cwd=REPO,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        self.messages: list[dict] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.messages.append(json.loads(line))

    def wait_for(self, ok, timeout: float = 30.0) -> dict:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.messages and ok(self.messages[-1]):
                return self.messages[-1]
            time.sleep(0.05)
        raise AssertionError(f"no such manual_control_setpoint; the last: {self.messages[-1:]}")

    def settle(self, quiet_s: float = 1.0) -> None:
        """Wait until nothing new has come for ``quiet_s``."""
        seen = -1
        while seen != len(self.messages):
            seen = len(self.messages)
            time.sleep(quiet_s)

    def close(self) -> None:
        self.proc.terminate()
        self.proc.wait(10)
