"""``[[process]]`` entries: supervised programs that are not modules (the simulated Pixhawk is one).

Checked with the profile; started before the modules with the placeholders replaced (and in the
environment); their death noticed (a critical one stops the stack with a failure, an ``on-failure`` one is
restarted); stopped after the modules; never outliving a killed supervisor.
"""

from __future__ import annotations

import re
import signal
import time
from pathlib import Path

import psutil
import pytest

from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import RunningStack, write_profile

SLEEPER = (
    'import os, sys, time; print("args", sys.argv[1:], os.environ.get("STACK_UDP_PORT"), flush=True); time.sleep(600)'
)


def profile(path: Path, process: str, module_args: str = "") -> Path:
    return write_profile(
        path,
        f"""
[stack]
vehicle = "sp1"
lockstep = false

[[process]]
{process}

[[module]]
module = "tests.support.modules:Pacer"
{module_args}
""",
    )


@pytest.mark.parametrize(
    ("process", "problem"),
    [
        ('name = "p"\ncommand = []', "process[0] (p).command: expected a non-empty list"),
        ('command = ["x"]', "process[0].name: missing"),
        ('name = "p"\ncommand = ["{nope}"]', "unknown placeholder {nope}"),
        ('name = "p"\ncommand = ["x"]\nrestart = "sometimes"', "'sometimes' is not one of"),
        ('name = "pacer"\ncommand = ["x"]', "process[0].name: 'pacer' is used twice"),
        ('name = "p"\ncommand = ["x"]\nready_after_s = 100.0', "ready_after_s: must be between"),
        ('name = "p"\ncommand = ["x"]\ncolour = 1', "process[0].colour: unknown key"),
    ],
)
def test_a_broken_process_entry_is_refused_with_the_key(tmp_path, process, problem):
    with pytest.raises(ProfileError, match=re.escape(problem)):
        load_profile(profile(tmp_path / "p.toml", process))


def test_process_entries_merge_by_name_and_placeholders_are_checked_in_module_args(tmp_path):
    base = profile(tmp_path / "base.toml", 'name = "p"\ncommand = ["{python}", "-V"]\ncritical = true')
    child = write_profile(
        tmp_path / "child.toml", 'extends = "base"\n[[process]]\nname = "p"\ncommand = ["{python}", "-c", "{seed}"]\n'
    )
    loaded = load_profile(child)
    (p,) = loaded.processes
    assert p.command == ["{python}", "-c", "{seed}"] and p.critical
    assert load_profile(base).processes[0].command == ["{python}", "-V"]


def test_a_process_starts_first_with_its_placeholders_and_stops_last(tmp_path):
    home = tmp_path / "home"
    command = f"""name = "sleeper"
command = ["{{python}}", "-c", '{SLEEPER}', "{{udp_port}}", "{{run_dir}}", "{{seed}}"]"""
    stack = RunningStack(home, profile(tmp_path / "p.toml", command))
    try:
        stack.wait_up()
        match = stack.wait_for(r"\[sleeper\] args \['(\d+)', '([^']+)', '1'\] (\d+)")
        assert match.group(1) == match.group(3)  # the same free port in the command and the environment
        assert Path(match.group(2)) == stack.run_dir()
        rows = {m["module"]: m for m in stack.status()["modules"]}
        assert rows["sleeper"]["type"] == "process" and rows["sleeper"]["state"] == "running"
        pid = rows["sleeper"]["pid"]
    finally:
        code = stack.stop(signal.SIGINT)
    assert code == 0
    out = stack.output
    assert out.index("process sleeper running") < out.index("starting pacer")
    assert out.index("[pacer] INFO    stopped") < out.rindex("[stack] stopped")
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE


def test_a_critical_process_that_dies_stops_the_stack_with_a_failure(tmp_path):
    home = tmp_path / "home"
    command = (
        'name = "doomed"\ncommand = ["{python}", "-c", "import time; time.sleep(4); raise SystemExit(3)"]\n'
        "critical = true"
    )
    stack = RunningStack(home, profile(tmp_path / "p.toml", command))
    assert stack.wait(timeout=120) != 0
    assert "process doomed failed with exit code 3" in stack.output
    assert "critical process doomed failed: stopping the stack" in stack.output


def test_an_on_failure_process_is_restarted(tmp_path):
    home = tmp_path / "home"
    command = (
        'name = "flaky"\ncommand = ["{python}", "-c", "import time; time.sleep(1.5); raise SystemExit(2)"]\n'
        'restart = "on-failure"\nmax_restarts = 1'
    )
    stack = RunningStack(home, profile(tmp_path / "p.toml", command))
    try:
        stack.wait_up()
        stack.wait_for(r"starting process flaky .*\n?", 30)
        deadline = time.monotonic() + 60
        while stack.output.count("starting process flaky") < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        assert stack.output.count("starting process flaky") == 2
    finally:
        stack.stop(signal.SIGINT)


def test_a_process_dies_with_a_killed_supervisor(tmp_path):
    home = tmp_path / "home"
    command = 'name = "sleeper"\ncommand = ["{python}", "-c", "import time; time.sleep(600)"]'
    stack = RunningStack(home, profile(tmp_path / "p.toml", command))
    try:
        stack.wait_up()
        pid = next(m["pid"] for m in stack.status()["modules"] if m["module"] == "sleeper")
        stack.proc.kill()  # SIGKILL: no clean stop
        stack.proc.wait()
        deadline = time.monotonic() + 20
        while psutil.pid_exists(pid) and psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
            assert time.monotonic() < deadline, "the process outlived its supervisor"
            time.sleep(0.1)
    finally:
        stack.kill()
