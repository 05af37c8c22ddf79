"""Run real stacks in tests: `stack up` as a subprocess, CLI commands against it, orphan checks."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import tomllib
from collections.abc import Callable, Iterator
from pathlib import Path

import psutil

from stack.bus.ports import free_port
from stack.runtime.pacing import SPEED_ENV

REPO = Path(__file__).resolve().parents[2]
# A MAVLink link of a launch profile: bound to a loopback UDP port, sending to another.
LINK_ARGS = re.compile(r'device = "udp:127\.0\.0\.1:\d+", remote = "127\.0\.0\.1:\d+"')


def eventually(ok: Callable[[], object], timeout: float = 30.0, what: str = "the condition", poll: float = 0.1) -> None:
    """Wait until ``ok()`` is true (a condition, never a fixed time); fail naming ``what`` after ``timeout``. Between
    two looks it waits ``poll``, or as long as the last look took if that is longer: looks that run a command (a
    ``stack status``, a process of its own) then take at most half the time, not all of it."""
    deadline = time.monotonic() + timeout
    while True:
        looked = time.monotonic()
        if ok():
            return
        now = time.monotonic()
        if now > deadline:
            raise AssertionError(f"{what}: not within {timeout:g} s")
        time.sleep(max(poll, now - looked))


def stack_env(home: Path) -> dict[str, str]:
    """The environment of a command a test runs: its STACK_HOME, a terminal's size asked of the terminal
    (pytest-xdist's workers set COLUMNS and LINES to 80 by 24), and lockstep stacks as fast as they go."""
    env = {k: v for k, v in os.environ.items() if k not in ("STACK_ENDPOINT", "COLUMNS", "LINES")}
    env["STACK_HOME"] = str(home)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    env["PYTHONUNBUFFERED"] = "1"
    env[SPEED_ENV] = "max"
    return env


def run_cli(home: Path, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "stack", *args],
        env=stack_env(home),
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=REPO,
    )


def cli_in_its_own_session(home: Path, *args: str) -> subprocess.Popen[str]:
    """``stack ARGS`` started as a terminal starts it, in a process group of its own (so a Ctrl-C can be sent
    to the whole group with ``os.killpg``), its output piped."""
    return subprocess.Popen(
        [sys.executable, "-m", "stack", *args],
        env=stack_env(home),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
        start_new_session=True,
    )


class RunningStack:
    """`stack up PROFILE ...` (or `stack fly SCENARIO ...` with ``command="fly"``) in the background, with its
    output collected line by line."""

    def __init__(self, home: Path, profile: Path | str, *args: str, command: str = "up") -> None:
        self.home = home
        self.lines: list[str] = []
        self._cond = threading.Condition()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "stack", command, str(profile), *args],
            env=stack_env(home),
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            cwd=REPO,
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line.rstrip("\n"))
                self._cond.notify_all()

    @property
    def output(self) -> str:
        with self._cond:
            return "\n".join(self.lines)

    def wait_for(self, pattern: str, timeout: float = 60.0) -> re.Match[str]:
        regex = re.compile(pattern)
        deadline = time.monotonic() + timeout
        with self._cond:
            seen = 0
            while True:
                for line in self.lines[seen:]:
                    m = regex.search(line)
                    if m:
                        return m
                seen = len(self.lines)
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    raise AssertionError(f"'{pattern}' not seen; output so far:\n{self.output}")
                self._cond.wait(min(left, 0.2))

    def wait_up(self, timeout: float = 90.0) -> None:
        self.wait_for(r"\[stack\] all \d+ modules up", timeout)

    def cli(self, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
        return run_cli(self.home, *args, timeout=timeout)

    def status(self) -> dict:
        out = self.cli("status", "--json")
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout)

    def subscribers(self, topic: str, instance: int = 0) -> list[str]:
        """Who subscribes to the topic, as the bus's graph announces it (`stack topic info`)."""
        out = self.cli("topic", "info", topic, "--json")
        assert out.returncode == 0, out.stderr
        rows = [row for row in json.loads(out.stdout)["instances"] if row["instance"] == instance]
        return rows[0]["subscribers"] if rows else []

    def module_pids(self) -> dict[str, int]:
        return {m["module"]: m["pid"] for m in self.status()["modules"] if m["pid"]}

    def run_dir(self) -> Path:
        return Path(self.wait_for(r"run directory (\S+)").group(1))

    def stop(self, sig: int = signal.SIGINT, timeout: float = 60.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            self._reader.join(timeout=5.0)
            raise AssertionError(f"the stack did not stop within {timeout:g} s of {sig!r}:\n{self.output}") from None
        finally:
            self.kill()
        self._reader.join(timeout=5.0)
        return code

    def wait(self, timeout: float = 120.0) -> int:
        code = self.proc.wait(timeout=timeout)
        self._reader.join(timeout=5.0)
        return code

    def kill(self) -> None:
        """Last-resort cleanup: the supervisor and anything started from this stack's home."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        for p in stack_processes(self.home):
            p.kill()


def stack_processes(home: Path) -> list[psutil.Process]:
    """Module processes whose spec lives under this STACK_HOME (i.e. started by a test's stack)."""
    found = []
    for p in psutil.process_iter(["cmdline"]):
        try:
            cmd = p.info["cmdline"] or []
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        if any(str(home) in part for part in cmd) and "stack.runtime.main" in cmd:
            found.append(p)
    return found


def wait_no_processes(home: Path, timeout: float = 10.0) -> list[psutil.Process]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        left = [p for p in stack_processes(home) if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
        if not left:
            return []
        time.sleep(0.1)
    return left


REFUSED = ("dropped a message holding", "ignored a message from publisher")
"""What a module logs when its input refuses a message (stack.runtime.inputs): never the stack's own."""


def refused_in_logs(home: Path) -> list[str]:
    """The log lines of every run under ``home`` where a module refused a message."""
    return [
        f"{log.name}: {line}"
        for log in sorted((home / "runs").glob("*/*.log"))
        for line in log.read_text(errors="replace").splitlines()
        if any(r in line for r in REFUSED)
    ]


def udp_port() -> int:
    return free_port(kind=socket.SOCK_DGRAM)


def free_links(text: str) -> str:
    """A profile's text with each MAVLink link bound to a free port and sending to another: the launch profiles'
    links have PX4 SITL's fixed ports, which two stacks of the test run could not both bind."""
    return LINK_ARGS.sub(lambda _: f'device = "udp:127.0.0.1:{udp_port()}", remote = "127.0.0.1:{udp_port()}"', text)


def launch_profile(directory: Path, name: str = "sitl_quad", extra: str = "") -> Path:
    """A copy of ``launch/NAME.toml`` (its name kept) in ``directory``, its links on free ports (:func:`free_links`);
    ``extra`` is appended."""
    text = free_links((REPO / "launch" / f"{name}.toml").read_text())
    assert "extends" not in tomllib.loads(text), f"{name} extends another profile, whose links would stay fixed"
    directory.mkdir(parents=True, exist_ok=True)
    return write_profile(directory / f"{name}.toml", text + extra)


def takeoff_when_ready(stack: RunningStack, *args: str) -> subprocess.CompletedProcess[str]:
    """``stack cmd takeoff ARGS --wait`` once arming is allowed: until the estimates have converged the
    commander refuses it for now (TEMPORARILY_REJECTED, saying which)."""
    deadline = time.monotonic() + 120.0
    while True:
        takeoff = stack.cli("cmd", "takeoff", *args, "--wait", timeout=300)
        if takeoff.returncode == 0 or time.monotonic() > deadline:
            return takeoff
        assert "TEMPORARILY_REJECTED" in takeoff.stderr, takeoff.stderr
        time.sleep(1.0)


def default_stack(home: Path, open_topics: tuple[str, ...] = ()) -> Iterator[RunningStack]:
    """`stack up` of the default profile for a module-scoped fixture: yields it running, then stops it
    and checks it stopped cleanly and left no process behind. ``open_topics``: topics the test publishes
    by hand although a module owns them (the profile's ``[stack] open_topics``)."""
    profile = launch_profile(home.parent / "profile")
    if open_topics:
        text = profile.read_text().replace("[stack]\n", f"[stack]\nopen_topics = {json.dumps(list(open_topics))}\n", 1)
        profile.write_text(text)
    running = RunningStack(home, profile, "--quiet")
    running.wait_up()
    yield running
    assert running.stop() == 0
    assert not wait_no_processes(home)


def write_profile(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def chain_profile(
    path: Path,
    *,
    lockstep: bool = True,
    seed: int = 7,
    tick_args: str = "",
    extra: str = "",
    transport: str = "shm",
    entries: dict[str, str] | None = None,
) -> Path:
    """The test processing chain: a tick source, a doubler, a summer and a timer module, with lockstep
    traffic over ``transport`` (shm, zenoh, or mixed: shared memory with the doubler and the pacer taking part
    over Zenoh); ``entries`` adds lines to modules' entries, by class name (TickSource, Doubler, Summer, Pacer),
    e.g. a restart policy or ``process = "NAME"``."""
    more = dict(entries or {})
    if transport == "mixed":
        transport = "shm"
        for name in ("Doubler", "Pacer"):
            more[name] = f'{more.get(name, "")}\ntransport = "zenoh"'.strip()
    return write_profile(
        path,
        f"""
[stack]
vehicle = "t1"
lockstep = {str(lockstep).lower()}
lockstep_transport = "{transport}"
seed = {seed}
stall_timeout_s = 4.0

[[module]]
module = "tests.support.modules:TickSource"
args = {{ {tick_args} }}
critical = true
{more.get("TickSource", "")}

[[module]]
module = "tests.support.modules:Doubler"
{more.get("Doubler", "")}

[[module]]
module = "tests.support.modules:Summer"
{more.get("Summer", "")}

[[module]]
module = "tests.support.modules:Pacer"
{more.get("Pacer", "")}
{extra}
""",
    )


def traced_chain(
    tmp_path: Path,
    name: str,
    steps: int,
    *,
    seed: int = 7,
    extra: str = "",
    transport: str = "shm",
    entries: dict[str, str] | None = None,
) -> tuple[Path, Path, Path]:
    """The test chain stopping after ``steps`` steps, with the tick source tracing each step and a probe module
    noting what it saw (see tests.support.modules): its profile, and where the trace and the probe's notes go."""
    trace, probe = tmp_path / f"{name}-trace.json", tmp_path / f"{name}-probe.json"
    profile = chain_profile(
        tmp_path / f"{name}.toml",
        seed=seed,
        tick_args=f'trace = "{trace}", steps = {steps}',
        extra=f'[[module]]\nmodule = "tests.support.modules:Probe"\nargs = {{ out = "{probe}" }}\n{extra}',
        transport=transport,
        entries=entries,
    )
    return profile, trace, probe


AUTONOMY_MODULES = ("local_position_estimator", "mc_hover_thrust_estimator", "flight_mode_manager", "mc_pos_control")


def attitude_only_profile(path: Path, extra: str = "") -> Path:
    """The default profile without position estimation, position control and navigation (the first-flight
    stack), keeping only the shared parameters its modules still have, its links on free ports; ``extra`` is
    appended."""
    from stack.runtime.spec import load_module_class

    doc = tomllib.loads(free_links((REPO / "launch" / "sitl_quad.toml").read_text()))
    doc["module"] = [m for m in doc["module"] if m["module"] not in AUTONOMY_MODULES]
    declared = {p.name for m in doc["module"] for p in load_module_class(m["module"]).PARAMS}
    doc["params"] = {k: v for k, v in doc["params"].items() if k in declared}
    return write_profile(path, toml_text(doc) + extra)


def toml_text(doc: dict) -> str:
    """TOML for a profile-shaped document: tables of scalars, inline tables, and an array of tables."""

    def value(v: object) -> str:
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return json.dumps(v)

    lines: list[str] = []
    for name, table in doc.items():
        rows = table if isinstance(table, list) else [table]
        for row in rows:
            lines.append(f"[[{name}]]" if isinstance(table, list) else f"[{name}]")
            lines.extend(f"{k} = {value(v)}" for k, v in row.items())
            lines.append("")
    return "\n".join(lines)
