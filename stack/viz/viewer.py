"""Where the plots go: a native Rerun viewer, the web viewer, an .rrd file.

Network exposure is opt-in: the viewer and web servers are the ``rerun`` executable started with
``--bind 127.0.0.1`` (the SDK's in-process ``serve_grpc`` binds 0.0.0.0 and takes a port but no address:
``rerun_bindings`` ``python_bridge::serve_grpc``), so nothing listens beyond loopback unless ``bind`` says so.

Rerun's usage analytics: the ``rerun`` executable reports "viewer opened"-style events unless
analytics are disabled. The processes started here get ``CI=1`` in their environment, which Rerun
0.41 treats as "analytics off" (``re_analytics`` pipeline), without touching the user's own Rerun
configuration; ``FORCE_RERUN_ANALYTICS=1`` in the environment still turns them on.
"""

from __future__ import annotations

import logging
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from stack.bus.ports import free_port
from stack.viz.display import DEFAULT_GRPC_PORT

LOOPBACK = "127.0.0.1"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
DEFAULT_WEB_PORT = 9090
START_TIMEOUT_S = 15.0

log = logging.getLogger("stack.viz")


def rerun_command() -> list[str]:
    """The ``rerun`` executable shipped with rerun-sdk (the ``rerun_cli`` package), called directly."""
    try:
        import rerun_cli

        binary = Path(rerun_cli.__file__).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
        if binary.exists():
            return [str(binary)]
    except ImportError:
        pass
    found = shutil.which("rerun")
    if found is None:
        raise RuntimeError("the rerun executable was not found (is rerun-sdk installed?)")
    return [found]


def viewer_environment() -> dict[str, str]:
    """The environment for Rerun processes: analytics off unless FORCE_RERUN_ANALYTICS asks for them."""
    env = dict(os.environ)
    env.setdefault("CI", "1")
    return env


def accepts_connections(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=0.2):
            return True
    except OSError:
        return False


def grpc_url(host: str, port: int) -> str:
    return f"rerun+http://{host}:{port}/proxy"


def web_viewer_url(host: str, web_port: int, proxy_url: str) -> str:
    return f"http://{host}:{web_port}/?url={urllib.parse.quote(proxy_url, safe='')}"


def _local_host(bind: str) -> str:
    """The address a local client uses to reach a server bound to ``bind``."""
    return LOOPBACK if bind in ("0.0.0.0", "::", "") else bind


class PlotSinks:
    """The outputs of one live plot session, set on a recording stream; closes what it started.

    - ``save``: an .rrd file path ("" for none).
    - ``web``: start ``rerun --serve-web`` bound to ``bind`` and stream to it; ``web_url`` is the
      address to open in a browser. The server stops with :meth:`close`, and with this process if it is
      killed. A port given (not 0) must be free: two web viewers never share one.
    - ``spawn``: stream to a native viewer on ``bind``:``grpc_port``, starting one (detached, it
      outlives the session like ``rr.spawn``'s) unless one already listens there. Ignored with ``web``.
    - ports of 0 pick free ones.
    """

    def __init__(
        self,
        rec: rr.RecordingStream,
        blueprint: rrb.Blueprint,
        *,
        save: str = "",
        web: bool = False,
        spawn: bool = False,
        bind: str = LOOPBACK,
        grpc_port: int = DEFAULT_GRPC_PORT,
        web_port: int = DEFAULT_WEB_PORT,
    ) -> None:
        self.rec = rec
        self.web_url: str | None = None
        self.viewer_url: str | None = None
        self.server: subprocess.Popen[bytes] | None = None
        host = _local_host(bind)
        if (web or spawn) and bind not in LOOPBACK_NAMES:
            log.warning("the Rerun viewer servers listen on %s: other machines can reach them", bind)
        sinks: list[rr.FileSink | rr.GrpcSink] = []
        if save:
            Path(save).parent.mkdir(parents=True, exist_ok=True)
            sinks.append(rr.FileSink(save))
        if web:
            for port in (grpc_port, web_port):
                if port and accepts_connections(host, port):
                    raise RuntimeError(f"port {port} on {host} is taken (another viewer?): choose another or 0 (any)")
            grpc_port = grpc_port or free_port(host)
            web_port = web_port or free_port(host)
            self.server = self._start(
                ["--serve-web", "--bind", bind, "--port", str(grpc_port), "--web-viewer-port", str(web_port)],
                detach=False,
            )
            self._wait_listening(host, (grpc_port, web_port), "rerun web viewer")
            self.viewer_url = grpc_url(host, grpc_port)
            self.web_url = web_viewer_url(host, web_port, self.viewer_url)
        elif spawn:
            grpc_port = grpc_port or free_port(host)
            if not accepts_connections(host, grpc_port):
                viewer = self._start(
                    ["--bind", bind, "--port", str(grpc_port), "--memory-limit", "75%", "--expect-data-soon"],
                    detach=True,
                )
                self._wait_listening(host, (grpc_port,), "rerun viewer", viewer)
            self.viewer_url = grpc_url(host, grpc_port)
        if self.viewer_url is not None:
            sinks.append(rr.GrpcSink(self.viewer_url))
        self.active = bool(sinks)
        if sinks:
            rec.set_sinks(*sinks, default_blueprint=blueprint)

    @staticmethod
    def _start(args: list[str], detach: bool) -> subprocess.Popen[bytes]:
        """A detached viewer outlives this process; the web server dies with it, even if it is killed. Either
        runs in a session of its own, so that a Ctrl-C in the terminal reaches this process only: it flushes
        what it still holds to the server before it stops it (else Rerun reports the severed connection)."""
        own = [] if detach else [sys.executable, "-m", "stack.supervisor.child", str(os.getpid())]
        return subprocess.Popen(
            [*own, *rerun_command(), *args],
            env=viewer_environment(),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )

    def _wait_listening(
        self, host: str, ports: tuple[int, ...], what: str, proc: subprocess.Popen[bytes] | None = None
    ) -> None:
        proc = proc or self.server
        assert proc is not None
        deadline = time.monotonic() + START_TIMEOUT_S
        while not all(accepts_connections(host, p) for p in ports):
            if proc.poll() is not None:
                raise RuntimeError(f"{what} exited with code {proc.returncode} (ports {ports} in use?)")
            if time.monotonic() > deadline:
                proc.kill()
                raise RuntimeError(f"{what} did not listen on {host}:{ports} within {START_TIMEOUT_S:g} s")
            time.sleep(0.05)

    def close(self) -> None:
        """Flush and disconnect the recording, then stop the web viewer server if this started one."""
        if self.active:
            self.rec.flush()
            self.rec.disconnect()
        if self.server is not None:
            self.server.terminate()
            try:
                self.server.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.server.kill()
                self.server.wait()
            self.server = None
