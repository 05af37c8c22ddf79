"""What a host's router denied, and to whom: counted from Zenoh's own account of its access control.

Zenoh drops a message its access rules deny without a word to the sender, and keeps no count of it (Zenoh 1.10). The
only trace is a log line of its access-control interceptor, at TRACE level
(``zenoh/src/net/routing/interceptor/access_control.rs``)::

    <zid> on Interface(eth0)+CertCommonName(gcs)+Transport(Tls)+<zid> is unauthorized to Put (ingress) on stack/...

The router's process turns that level on for that interceptor alone and passes its standard output, where Zenoh's
log goes, through a filter of its own (stack/security/log_filter.py): a denial goes to a pipe this module reads and
counts, the interceptor's other lines nowhere, every other line to where the standard output went before. Zenoh
logs each message it lets through at that level too, a line per message the router passes, which is why only a
router with access rules does it (``benchmarks/bench_hosts.py`` gives what it costs a hop).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import queue
import re
import select
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import zenoh

from stack.security.log_filter import TARGET

_WHAT = r"is unauthorized to (?P<action>[A-Za-z/ ]+?) \((?P<flow>ingress|egress)\) on (?P<key>\S+)"
_EVALUATED = re.compile(r"(?P<zid>[0-9a-f]+) on (?P<subject>\S+) " + _WHAT)
_CACHED = re.compile(r"Using cached result: (?P<zid>[0-9a-f]+) " + _WHAT)
_COLOUR = re.compile(r"\x1b\[[0-9;]*m")
_SUBJECT_PART = re.compile(r"(\w+)\(([^)]*)\)")
_FILTER = [sys.executable, "-S", str(Path(__file__).with_name("log_filter.py"))]
LOG_PIPE_BYTES = 1 << 20
"""Room in the pipe to the filter for a burst of the log (a line per message passed): Zenoh's thread writing it waits
when it is full."""
EVALUATION_WINDOW_S = 0.05
"""How long the lines of one evaluation of a key may take to arrive (they are written together, microseconds apart)."""


@dataclass(frozen=True)
class Denial:
    """One message a router refused: who sent it (or was to receive it), what it was, which way, on which key."""

    who: str
    """The certificate's common name, else the network interface it came by."""
    action: str
    """Zenoh's kind of message, in the words of the access rules (``put``, ``declare_subscriber``, ``query``...)."""
    flow: str
    key: str

    def describe(self) -> str:
        return f"denied {self.who} a {self.action} ({self.flow}) on {self.key}"


def _action(text: str) -> str:
    return text.strip().lower().replace("declare/undeclare", "declare").replace(" ", "_")


@dataclass
class _Evaluation:
    since: float
    denials: list[Denial] = field(default_factory=list)


class DenialReader:
    """The messages really denied, from Zenoh's log lines of its access control.

    Zenoh writes such a line for each message it drops, and also, when a session first declares a key (a subscriber,
    a publisher, a token), for each kind of message it would drop on that key, which it then keeps; a message later
    sent on that key is told as ``Using cached result: <zid> ...``, without its subject. So: a cached line is a
    message denied, its sender named by the zid's earlier lines; lines for one zid and key that name several kinds of
    message within :data:`EVALUATION_WINDOW_S` are an evaluation, not messages; a line alone is a message denied."""

    def __init__(self) -> None:
        self.names: dict[str, str] = {}
        self.pending: dict[tuple[str, str], _Evaluation] = {}

    def feed(self, line: str, now: float) -> list[Denial]:
        """The denials ``line`` (received at ``now``, monotonic seconds) completes, oldest first."""
        text = _COLOUR.sub("", line)
        done = self.flush(now)
        if (cached := _CACHED.search(text)) is not None:
            who = self.names.get(cached["zid"], f"zenoh id {cached['zid']}")
            done.append(Denial(who, _action(cached["action"]), cached["flow"], cached["key"]))
        elif (found := _EVALUATED.search(text)) is not None:
            parts = dict(_SUBJECT_PART.findall(found["subject"]))
            who = parts.get("CertCommonName") or f"interface {parts.get('Interface', '?')}"
            self.names[found["zid"]] = who
            evaluation = self.pending.setdefault((found["zid"], found["key"]), _Evaluation(now))
            evaluation.denials.append(Denial(who, _action(found["action"]), found["flow"], found["key"]))
        return done

    def flush(self, now: float | None = None) -> list[Denial]:
        """The denials whose lines have all arrived by ``now`` (None: all that are waiting)."""
        done = []
        for at, evaluation in list(self.pending.items()):
            if now is None or now - evaluation.since >= EVALUATION_WINDOW_S:
                del self.pending[at]
                if len({(d.action, d.flow) for d in evaluation.denials}) == 1:
                    done.extend(evaluation.denials)
        return done


@dataclass
class DenialCounts:
    """How often each (who, what, which way, key) was denied, and when last (seconds since the epoch)."""

    counts: dict[Denial, int] = field(default_factory=dict)
    last: dict[Denial, float] = field(default_factory=dict)

    def add(self, denial: Denial, at: float) -> bool:
        """Count ``denial``; True the first time it is seen."""
        first = denial not in self.counts
        self.counts[denial] = self.counts.get(denial, 0) + 1
        self.last[denial] = at
        return first

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    def rows(self) -> list[dict[str, object]]:
        """One row per kind of denial, most frequent first (for ``stack status --json``)."""
        ordered = sorted(self.counts, key=lambda d: (-self.counts[d], d.who, d.key, d.action))
        return [
            {"who": d.who, "action": d.action, "flow": d.flow, "key": d.key, "count": self.counts[d],
             "last": self.last[d]}
            for d in ordered
        ]  # fmt: skip


_watching: list[Callable[[Denial], None]] = []
_lock = threading.Lock()


def watch_denials(on_denial: Callable[[Denial], None]) -> None:
    """Call ``on_denial`` (on a thread of its own) for each message the routers of this process deny.

    Call it before the process's first Zenoh session opens: Zenoh's log is set up once per process, and the filter is
    started before any session exists (a process never forks once one is open). A ``RUST_LOG`` given by the user is
    kept, its lines passed through."""
    with _lock:
        if on_denial in _watching:
            return
        _watching.append(on_denial)
        if len(_watching) > 1:
            return
        user = os.environ.get("RUST_LOG", "")
        directives = f"{user or 'off'},{TARGET.decode()}=trace"
        log_read, log_write = os.pipe()
        denied_read, denied_write = os.pipe()
        # its own session: Ctrl-C on the terminal must not stop it while the router still writes to it
        subprocess.Popen(_FILTER, stdin=log_read, stderr=denied_write, start_new_session=True, close_fds=True)
        os.close(log_read)
        os.close(denied_write)
        with contextlib.suppress(OSError):  # beyond the user's share of pipe memory: the default 64 kB
            fcntl.fcntl(log_write, fcntl.F_SETPIPE_SZ, LOG_PIPE_BYTES)
        os.dup2(log_write, 1)
        os.close(log_write)
        told: queue.SimpleQueue[Denial | None] = queue.SimpleQueue()
        threading.Thread(target=_read_denials, args=(denied_read, told), name="denials", daemon=True).start()
        threading.Thread(target=_tell, args=(told,), name="denials-told", daemon=True).start()
        os.environ.pop("RUST_LOG", None)
        try:
            zenoh.init_log_from_env_or(directives)
        finally:
            if user:
                os.environ["RUST_LOG"] = user


def _read_denials(fd: int, told: queue.SimpleQueue[Denial | None]) -> None:
    """Read the filter's denials as they come, never blocking on anything else: the filter would block writing them,
    and Zenoh's router writing its log to the filter."""
    reader = DenialReader()
    partial = b""
    while True:
        readable, _, _ = select.select([fd], [], [], EVALUATION_WINDOW_S)
        chunk = os.read(fd, 65536) if readable else b""
        if readable and not chunk:
            for denial in reader.flush():
                told.put(denial)
            told.put(None)
            return
        *lines, partial = (partial + chunk).split(b"\n")
        now = time.monotonic()
        for line in lines:
            for denial in reader.feed(line.decode(errors="replace"), now):
                told.put(denial)
        for denial in reader.flush(now):
            told.put(denial)


def _tell(told: queue.SimpleQueue[Denial | None]) -> None:
    """Tell the watchers (who may print: to the standard output, through the filter) on a thread of its own."""
    while (denial := told.get()) is not None:
        with _lock:
            callbacks = list(_watching)
        for on_denial in callbacks:
            on_denial(denial)
