"""No module outlives its supervisor: SIGKILL of `stack up` (nothing cleaned up, no signal sent on) while the
default stack starts and while it flies; every module process ends on its own soon after.
benchmarks/bench_orphans.py kills it 100 times at random moments."""

from __future__ import annotations

import pytest

from tests.support.harness import (
    RunningStack,
    launch_profile,
    stack_processes,
    takeoff_when_ready,
    wait_no_processes,
)

pytestmark = pytest.mark.flight

# A module ends within a second of its supervisor (stack.runtime.orphan); the margin is for a loaded machine.
GONE_WITHIN_S = 10.0


@pytest.mark.parametrize("moment", ["starting", "flying"])
def test_every_module_ends_when_its_supervisor_is_killed(tmp_path, moment: str) -> None:
    home = tmp_path / "home"
    stack = RunningStack(home, launch_profile(tmp_path / "profile"), "--quiet")
    try:
        if moment == "starting":
            stack.wait_for(r"starting commander")
        else:
            stack.wait_up()
        if moment == "flying":
            takeoff = takeoff_when_ready(stack, "--alt", "3")
            assert takeoff.returncode == 0, takeoff.stderr
        assert stack_processes(home), "no module process was running"
        stack.proc.kill()
        stack.proc.wait()
        left = wait_no_processes(home, timeout=GONE_WITHIN_S)
        assert not left, [p.cmdline() for p in left]
    finally:
        stack.kill()
