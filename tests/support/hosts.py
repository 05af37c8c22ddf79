"""Hosts for tests of one vehicle spread over several machines: each host a Linux network namespace, all of
them joined by veth links to a bridge in a "switch" namespace of its own.

- Nothing is added to the root namespace: the bridge lives in the switch namespace, and each veth pair is
  created with its ends directly in the host's and the switch's namespaces.
- Any two networks can exist at once (pytest-xdist's workers, two test runs on one machine): every namespace
  name carries the process id and a random token. Interface names (``eth0`` on a host, ``br0`` and ``p<i>``
  in the switch) live in their own namespace and need not be unique on the machine.
- Clean-up always happens, even when set-up fails half-way: it is registered before anything is created, and
  it kills every process left in the namespaces (SIGTERM, then SIGKILL after a grace) before deleting them.
- Host ``i`` (0-based, in the order named) is ``10.88.0.<i+1>/24`` on its ``eth0``; ``lo`` is up, so
  ``127.0.0.1`` inside a host is that host's own, never the machine's.
- The tests skip, saying why, where namespaces cannot be made (not root, no ``ip``, creation refused).
"""

from __future__ import annotations

import contextlib
import functools
import os
import secrets
import shutil
import signal
import subprocess
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import psutil
import pytest

SUBNET = "10.88.0"
HOST_IFACE = "eth0"
BRIDGE = "br0"

needs_netns = pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("ip") is None,
    reason="network namespaces need root and iproute2's `ip`",
)


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    """Run ``ip ARGS``; on failure (with ``check``) raise an error that carries ip's own message."""
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=30)
    if check and done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip() or f'exit status {done.returncode}'}")
    return done


def _unique_prefix() -> str:
    return f"stk-{os.getpid()}-{secrets.token_hex(4)}"


@functools.cache
def _netns_refused() -> str | None:
    """Why this machine refuses to make a network namespace, or None where it makes one (tried once)."""
    probe = f"{_unique_prefix()}-probe"
    made = _ip("netns", "add", probe, check=False)
    _ip("netns", "del", probe, check=False)
    return None if made.returncode == 0 else f"cannot make a network namespace: {made.stderr.strip()}"


def require_netns() -> None:
    """Skip the calling test, saying why, where network namespaces cannot be made."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("network namespaces need root")
    if shutil.which("ip") is None:
        pytest.skip("network namespaces need iproute2's `ip`")
    refused = _netns_refused()
    if refused:
        pytest.skip(refused)


def namespace_pids(netns: str) -> list[int]:
    """The processes running in the network namespace ``netns`` (none once it is gone)."""
    return [int(pid) for pid in _ip("netns", "pids", netns, check=False).stdout.split()]


@dataclass
class Host:
    """One machine of the network: a namespace, its address on the bridge, and a STACK_HOME of its own."""

    name: str
    netns: str
    address: str
    home: Path
    switch: str = field(repr=False)
    port: str = field(repr=False)  # its link's end in the switch namespace
    clock_ahead_s: int = 0
    """Its CLOCK_MONOTONIC this far ahead of the test machine's (a time namespace of its own), as another machine's."""
    processes: list[subprocess.Popen[str]] = field(default_factory=list, repr=False)

    def command(self, *args: str) -> list[str]:
        """``args`` as a command run on this host."""
        ahead = ("unshare", "--time", "--monotonic", str(self.clock_ahead_s), "--fork", "--kill-child")
        return ["ip", "netns", "exec", self.netns, *(ahead if self.clock_ahead_s else ()), *args]

    def environment(self, env: Mapping[str, str] | None) -> dict[str, str]:
        """``env``, or by default the caller's environment with this host's STACK_HOME."""
        return dict(env) if env is not None else {**os.environ, "STACK_HOME": str(self.home)}

    def run(
        self, *args: str, env: Mapping[str, str] | None = None, timeout: float = 60.0, **kw: Any
    ) -> subprocess.CompletedProcess[str]:
        """Run ``args`` on this host to its end, its output captured as text."""
        kw.setdefault("capture_output", True)
        return subprocess.run(self.command(*args), env=self.environment(env), timeout=timeout, text=True, **kw)

    def popen(
        self, *args: str, env: Mapping[str, str] | None = None, niceness: int = 0, **kw: Any
    ) -> subprocess.Popen[str]:
        """Start ``args`` on this host in a session of its own; the network's clean-up ends it. A ``niceness`` is
        the whole session's: where Linux's autogroups are on, the scheduler weighs each session as one against the
        others, so a niceness within a session of one process alone would change nothing (sched(7))."""
        if niceness:
            nice = f'{{ echo {niceness} > /proc/self/autogroup; }} 2>/dev/null; exec nice -n {niceness} "$@"'
            args = ("sh", "-c", nice, "sh", *args)
        process = subprocess.Popen(
            self.command(*args), env=self.environment(env), start_new_session=True, text=True, **kw
        )
        self.processes.append(process)
        return process

    def link_down(self) -> None:
        """Cut the host off the network (its end of the link goes down; it keeps its address)."""
        _ip("-n", self.netns, "link", "set", HOST_IFACE, "down")

    def link_up(self) -> None:
        """Reconnect the host."""
        _ip("-n", self.netns, "link", "set", HOST_IFACE, "up")

    def limit_rate(self, rate: str = "1mbit") -> None:
        """Limit what the host sends and what it receives to ``rate`` (``tc`` units: ``1mbit``, ``500kbit``):
        a token bucket on its own link's egress and on the switch's egress towards it."""
        for netns, iface in ((self.netns, HOST_IFACE), (self.switch, self.port)):
            done = subprocess.run(
                ["tc", "-n", netns, "qdisc", "replace", "dev", iface, "root", "tbf", "rate", rate,
                 "burst", "32kbit", "latency", "400ms"],
                capture_output=True, text=True, timeout=30,
            )  # fmt: skip
            if done.returncode != 0:
                raise RuntimeError(f"tc on {iface} in {netns}: {done.stderr.strip()}")


class Network:
    """Hosts named ``names`` on one bridge, their STACK_HOMEs under ``base``; on clean-up, processes left in
    the namespaces get ``grace`` seconds between SIGTERM and SIGKILL.

    Making the object creates nothing: ``start()`` does, after the caller has registered ``close()`` (as the
    ``network`` fixture does); as a context manager it starts, and closes even when the start fails.
    """

    def __init__(
        self, names: Sequence[str], base: Path, grace: float = 5.0, clock_ahead_s: Mapping[str, int] | None = None
    ) -> None:
        self.grace = grace
        prefix = _unique_prefix()
        self.switch = f"{prefix}-switch"
        self.hosts: dict[str, Host] = {
            name: Host(
                name=name,
                netns=f"{prefix}-host-{name}",
                address=f"{SUBNET}.{i + 1}",
                home=base / name,
                switch=self.switch,
                port=f"p{i + 1}",
                clock_ahead_s=(clock_ahead_s or {}).get(name, 0),
            )
            for i, name in enumerate(names)
        }
        if len(self.hosts) != len(names):
            raise ValueError(f"host names repeat: {list(names)}")

    @property
    def namespaces(self) -> list[str]:
        """Every namespace this network is made of, made yet or not."""
        return [self.switch, *(host.netns for host in self.hosts.values())]

    def start(self) -> Network:
        _ip("netns", "add", self.switch)
        _ip("-n", self.switch, "link", "add", BRIDGE, "type", "bridge")
        _ip("-n", self.switch, "link", "set", BRIDGE, "up")
        for host in self.hosts.values():
            host.home.mkdir(parents=True, exist_ok=True)
            _ip("netns", "add", host.netns)
            _ip("-n", host.netns, "link", "set", "lo", "up")
            # Both ends made directly in their namespaces: the veth pair never appears in the root namespace.
            _ip("link", "add", HOST_IFACE, "netns", host.netns, "type", "veth", "peer", "name", host.port,
                "netns", self.switch)  # fmt: skip
            _ip("-n", self.switch, "link", "set", host.port, "master", BRIDGE, "up")
            _ip("-n", host.netns, "addr", "add", f"{host.address}/24", "dev", HOST_IFACE)
            _ip("-n", host.netns, "link", "set", HOST_IFACE, "up")
        return self

    def close(self) -> None:
        """End every process in the network's namespaces, then delete them (what exists of them)."""
        _signal(self._running(), signal.SIGTERM)
        deadline = time.monotonic() + self.grace
        while (left := self._running()) and time.monotonic() < deadline:
            time.sleep(0.05)
        _signal(left, signal.SIGKILL)
        for host in self.hosts.values():
            for process in host.processes:
                process.wait()
        for netns in self.namespaces:
            _ip("netns", "del", netns, check=False)

    def _running(self) -> set[int]:
        """The processes still running in the network: in its namespaces, or started by ``popen``."""
        pids = {pid for netns in self.namespaces for pid in namespace_pids(netns)}
        pids.update(p.pid for host in self.hosts.values() for p in host.processes if p.poll() is None)
        return {pid for pid in pids if alive(pid)}

    def __enter__(self) -> Network:
        try:
            return self.start()
        except BaseException:
            self.close()
            raise

    def __exit__(self, *exc: object) -> None:
        self.close()


def _signal(pids: set[int], sig: signal.Signals) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, sig)


def alive(pid: int) -> bool:
    """Whether ``pid`` still runs (a zombie has ended: it only waits for its parent to collect it)."""
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


@pytest.fixture
def network(request: pytest.FixtureRequest, tmp_path: Path) -> Callable[..., Network]:
    """``network(["sim", "control"])``: a started network of those hosts, cleaned up after the test (skips
    where network namespaces cannot be made); ``clock_ahead_s={"control": 100}`` sets a host's clock ahead."""
    require_netns()
    count = 0

    def make(names: Sequence[str], clock_ahead_s: Mapping[str, int] | None = None) -> Network:
        nonlocal count
        count += 1
        net = Network(names, tmp_path / f"network-{count}", clock_ahead_s=clock_ahead_s)
        request.addfinalizer(net.close)
        return net.start()

    return make
