"""The web viewer of `stack up --web` belongs to its stack: ports and URL of its own, shown with --quiet, gone with
the stack or its bridge. Real stacks on loopback; no display needed."""

import re
import signal
import time
import urllib.request

import psutil

from stack.viz.viewer import accepts_connections
from tests.support.harness import RunningStack, chain_profile, wait_no_processes

URL = r"\[rerun_bridge\] INFO\s+web viewer: (http://127\.0\.0\.1:(\d+)/\?url=rerun%2Bhttp%3A%2F%2F127\.0\.0\.1%3A(\d+)\S*)"


def web_stack(tmp_path, vehicle: str) -> RunningStack:
    """A `stack up --web --quiet` of its own (home included: the harness's clean-up kills by home)."""
    home = tmp_path / vehicle
    profile = chain_profile(tmp_path / f"{vehicle}.toml", lockstep=False)
    profile.write_text(profile.read_text().replace('vehicle = "t1"', f'vehicle = "{vehicle}"'))
    return RunningStack(home, profile, "--web", "--quiet")


def serves(url: str) -> bool:
    with urllib.request.urlopen(url.split("?")[0], timeout=10) as page:
        return page.status == 200


def gone(proc: psutil.Process, ports: tuple[int, ...], timeout: float = 15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        dead = not proc.is_running() or proc.status() == psutil.STATUS_ZOMBIE
        if dead and not any(accepts_connections("127.0.0.1", p) for p in ports):
            return True
        time.sleep(0.1)
    return False


def test_each_web_stack_has_its_own_viewer_which_ends_with_it(tmp_path):
    first, second = web_stack(tmp_path, "w1"), web_stack(tmp_path, "w2")
    try:
        viewers = []
        for stack in (first, second):
            found = stack.wait_for(URL)
            stack.wait_up()
            bridge = psutil.Process(int(stack.wait_for(r"starting rerun_bridge \(pid (\d+)\)").group(1)))
            (server,) = bridge.children(recursive=True)
            viewers.append((found.group(1), (int(found.group(2)), int(found.group(3))), bridge, server))
        (url1, ports1, _, server1), (url2, ports2, bridge2, server2) = viewers
        assert url1 != url2 and not set(ports1) & set(ports2)
        assert serves(url1) and serves(url2)
        for stack in (first, second):  # --quiet hides the modules' logs, not the URL
            assert not re.search(r"^\[(doubler|summer|pacer)\]", stack.output, re.M)

        assert first.stop(signal.SIGINT) == 0
        assert gone(server1, ports1)
        assert serves(url2)
        # A bridge killed outright (no clean-up) takes its viewer with it.
        bridge2.kill()
        second.wait_for(r"rerun_bridge failed with exit code -9")
        assert gone(server2, ports2)
        assert second.stop(signal.SIGINT) == 1  # a module failed
    finally:
        for stack in (first, second):
            stack.kill()
    for stack in (first, second):
        assert not wait_no_processes(stack.home)
