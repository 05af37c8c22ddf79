"""The fast path leaves nothing behind: no shared-memory segment, FIFO or socket file, however the stack ends.

Its region is a memfd and its wake-ups are eventfds, inherited by the module processes: they have no
name anywhere and vanish with the last process holding them.
"""

import contextlib
import os
import signal
import stat
from pathlib import Path

import psutil
import pytest

from tests.support.harness import RunningStack, chain_profile, eventually, stack_processes, wait_no_processes

SHM = Path("/dev/shm")


def special_files(root: Path) -> list[Path]:
    """FIFOs, sockets and other non-regular files under ``root``."""
    found = []
    for path in root.rglob("*"):
        mode = path.lstat().st_mode
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
            found.append(path)
    return found


def left_in_shm(before: set[Path]) -> list[Path]:
    """Files that appeared in /dev/shm and that no live process maps (those of other programs still running
    on the machine are theirs, not leftovers)."""
    mapped = set()
    for maps in Path("/proc").glob("[0-9]*/maps"):
        try:
            mapped.update(line.split()[-1] for line in maps.read_text().splitlines() if "/dev/shm/" in line)
        except OSError:
            continue
    return [p for p in set(SHM.iterdir()) - before if str(p) not in mapped]


def holds_region(pid: int) -> bool:
    fds = Path(f"/proc/{pid}/fd")
    try:
        return any("memfd:stack-fastpath" in os.readlink(fd) for fd in fds.iterdir())
    except OSError:
        return False


@pytest.mark.parametrize("ending", ["stop", "module crash", "supervisor killed"])
def test_nothing_is_left_behind(tmp_path, ending):
    home = tmp_path / "home"
    shm_before = set(SHM.iterdir())
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml"))
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep starting")
        pids = stack.module_pids()
        assert all(holds_region(pid) for pid in pids.values())
        assert holds_region(stack.proc.pid)
        if ending == "module crash":
            os.kill(pids["summer"], signal.SIGKILL)
            stack.wait_for(r"summer failed with exit code -9")
        if ending == "supervisor killed":
            stack.proc.kill()
            stack.proc.wait()
        else:
            stack.stop()
        assert not wait_no_processes(home, timeout=15.0)
    finally:
        stack.kill()
    with contextlib.suppress(AssertionError):  # the assertions below say what is left
        eventually(lambda: not left_in_shm(shm_before) and not stack_processes(home), what="everything gone")
    assert left_in_shm(shm_before) == []
    assert special_files(home) == []
    assert not any(holds_region(p.pid) for p in stack_processes(home))
    assert not psutil.pid_exists(stack.proc.pid) or not holds_region(stack.proc.pid)
