"""Modules that share a process (``process = "NAME"``): the same run, message for message, in fewer processes.

The test chain (tests.support.modules) with the tick source and the doubler in one process (the lockstep's
coordinator runs its member while it waits for the step to end) and the summer and the pacer in another (two
members served by one thread), against the chain with every module its own process. Each module of a shared
process keeps its status row, heartbeat and parameters; the process's death is every module's, and a restart
brings them all back into the lockstep. In real time the process's thread runs each module on its own timer or
trigger, and a crash restarts them all as well.
"""

import json
import os
import signal

import pytest

from stack.supervisor.profile import ProfileError, load_profile
from tests.support.harness import (
    RunningStack,
    chain_profile,
    eventually,
    traced_chain,
    wait_no_processes,
    write_profile,
)

STEPS = 2000
TWO_PROCESSES = {
    "TickSource": 'process = "clock"',
    "Doubler": 'process = "clock"',
    "Summer": 'process = "chain"',
    "Pacer": 'process = "chain"',
}
RESTARTS = 'restart = "on-failure"\nmax_restarts = 2'


def run_chain(tmp_path, name: str, processes: dict[str, str] | None) -> tuple[list, list, str]:
    """The chain's lockstep trace and probe, and the stack's output; ``processes``: chain_profile's entries."""
    home = tmp_path / f"home-{name}"
    profile, trace, probe = traced_chain(tmp_path, name, STEPS, entries=processes)
    stack = RunningStack(home, profile)
    code = stack.wait(timeout=300)
    assert code == 0, stack.output
    assert not wait_no_processes(home)
    return json.loads(trace.read_text()), json.loads(probe.read_text()), stack.output


def test_modules_sharing_processes_run_the_same_lockstep_message_for_message(tmp_path):
    trace_own, probe_own, _ = run_chain(tmp_path, "own", None)
    trace_shared, probe_shared, output = run_chain(tmp_path, "shared", TWO_PROCESSES)
    assert "process clock: tick_source, doubler" in output
    assert "process chain: summer, pacer" in output
    assert len(trace_own) == STEPS - 1
    assert trace_shared == trace_own
    assert probe_shared[: STEPS - 1] == probe_own[: STEPS - 1]


def test_a_shared_process_that_dies_takes_its_modules_and_comes_back_with_them(tmp_path):
    home = tmp_path / "home"
    pair = f'{RESTARTS}\nprocess = "pair"'
    profile = chain_profile(tmp_path / "chain.toml", entries={"Doubler": pair, "Summer": pair})
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep starting")
        rows = {m["module"]: m for m in stack.status()["modules"]}
        # A row per module, each naming the process it shares.
        assert rows["doubler"]["pid"] == rows["summer"]["pid"] != rows["pacer"]["pid"]
        assert rows["doubler"]["process"] == rows["summer"]["process"] == "pair"
        assert rows["pacer"]["process"] == "pacer"
        assert rows["summer"]["state"] == rows["doubler"]["state"] == "running"
        table = stack.cli("status").stdout.splitlines()
        assert "PROCESS" in next(line for line in table if line.startswith("MODULE"))
        assert next(line for line in table if line.startswith("summer")).split()[1] == "pair"
        eventually(lambda: sim_time(stack) > 500_000, what="half a simulated second")
        os.kill(rows["doubler"]["pid"], signal.SIGKILL)
        stack.wait_for(r"process pair \(doubler, summer\) failed with exit code -9")
        stack.wait_for(r"restarting process pair \(doubler, summer\) \(restart 1\)", timeout=30)
        for name in ("doubler", "summer"):
            stack.wait_for(rf"lockstep: {name} admitted at t=", timeout=60)
        t1 = sim_time(stack)
        eventually(lambda: sim_time(stack) > t1 + 1_000_000, what="a simulated second with the pair back")
        rows = {m["module"]: m for m in stack.status()["modules"]}
        assert rows["doubler"]["pid"] == rows["summer"]["pid"] != 0
        for name in ("doubler", "summer"):
            assert rows[name]["restarts"] == 1 and rows[name]["runs"] > 100, rows[name]
    finally:
        assert stack.stop() == 1  # the pair failed once
    assert "stalled" not in stack.output
    assert not wait_no_processes(home)


def test_a_shared_process_with_a_module_that_may_not_restart_stays_down(tmp_path):
    """The tick source (the lockstep's clock, critical, no restart) shares its process with a doubler that would
    restart: the process is not restarted, the tick source has failed, and the stack stops."""
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml",
        entries={"TickSource": 'process = "clock"', "Doubler": f'{RESTARTS}\nprocess = "clock"'},
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep starting")
        os.kill(stack.module_pids()["doubler"], signal.SIGKILL)
        stack.wait_for(r"process clock \(tick_source, doubler\) failed with exit code -9")
        stack.wait_for(r"critical module tick_source failed: stopping the stack")
        assert stack.wait(timeout=60) == 1
    finally:
        stack.stop()
    assert "restarting process clock" not in stack.output
    assert not wait_no_processes(home)


def sim_time(stack: RunningStack) -> int:
    return max(m.get("sim_time_us", 0) for m in stack.status()["modules"])


def test_in_real_time_the_modules_of_a_process_all_run_and_a_crash_restarts_them_all(tmp_path):
    """In real time the chain in two processes, with a crasher beside the summer and the pacer: every module runs
    (the summer on the doubler's messages from the other process, the pacer on its timer), then the crasher's exit
    ends its process, which comes back with all three."""
    home = tmp_path / "home"
    marker = tmp_path / "crasher-pids"
    chain = f'{RESTARTS}\nprocess = "chain"'
    crasher = f'[[module]]\nmodule = "tests.support.modules:Crasher"\nargs = {{ ticks = 60, marker = "{marker}" }}\n'
    profile = chain_profile(
        tmp_path / "chain.toml",
        lockstep=False,
        entries={**TWO_PROCESSES, "Summer": chain, "Pacer": chain},
        extra=f"{crasher}{chain}\n",
    )
    stack = RunningStack(home, profile)
    try:
        stack.wait_up()
        assert "process clock: tick_source, doubler" in stack.output
        assert "process chain: summer, pacer, crasher" in stack.output
        pids = stack.module_pids()
        assert pids["tick_source"] == pids["doubler"] != pids["summer"] == pids["pacer"] == pids["crasher"]

        def runs() -> dict[str, int]:
            return {m["module"]: m.get("runs", 0) for m in stack.status()["modules"]}

        eventually(lambda: min(runs().values()) > 20, what="every module running")
        stack.wait_for(r"process chain \(summer, pacer, crasher\) failed with exit code 4", timeout=30)
        stack.wait_for(r"restarting process chain \(summer, pacer, crasher\) \(restart 1\)", timeout=30)
        eventually(lambda: stack.module_pids()["summer"] != pids["summer"], what="the chain's process started again")
        again = stack.module_pids()
        assert again["summer"] == again["pacer"] == again["crasher"]
        assert again["doubler"] == pids["doubler"]
        assert len(set(marker.read_text().split())) == 2  # the crasher started twice
        eventually(lambda: runs()["summer"] > 20 and runs()["pacer"] > 20, what="the chain running again")
    finally:
        assert stack.stop() == 1  # the chain's process failed
    assert not wait_no_processes(home)


@pytest.mark.parametrize(
    ("entry", "problem"),
    [
        ('module = "recorder"\nprocess = "all"', "recorder reads on the wall clock beside the lockstep"),
        ('module = "mavlink"\nprocess = "all"', "mavlink runs outside the lockstep"),
        ('module = "commander"\nprocess = "a b"', "invalid process name 'a b'"),
        ('module = "commander"\nprocess = "simulator"', "'simulator' is also the name of simulator"),
    ],
)
def test_a_process_no_module_can_share_is_refused_naming_the_key(tmp_path, entry, problem):
    path = write_profile(
        tmp_path / "grouped.toml", f'[stack]\nlockstep = true\n[[module]]\nmodule = "simulator"\n[[module]]\n{entry}\n'
    )
    with pytest.raises(ProfileError) as refused:
        load_profile(path)
    assert f"{path}: module[1]" in str(refused.value) or f"{path}: module (" in str(refused.value)
    assert ".process: " in str(refused.value) and problem in str(refused.value)


def test_a_process_over_two_hosts_is_refused(tmp_path):
    entries = "".join(f'[[module]]\nname = "{name}"\nprocess = "both"\n' for name in ("simulator", "commander"))
    path = write_profile(tmp_path / "split.toml", f'extends = "sitl_quad_hosts"\n{entries}')
    with pytest.raises(ProfileError) as refused:
        load_profile(path)
    problem = "module (commander).process: 'both' also holds simulator, on host sim; a process runs on one host"
    assert f"{path} (extends " in str(refused.value) and problem in str(refused.value)


def test_the_split_vehicle_shares_a_process_on_each_host(tmp_path):
    profile = load_profile("sitl_quad_hosts")
    groups: dict[str, set[str]] = {}
    for m in profile.modules:
        if m.process:
            groups.setdefault(f"{m.host}/{m.process}", set()).add(m.name)
    assert groups == {
        "sim/simulation": {"simulator", "attitude_estimator_q", "local_position_estimator"},
        "control/flight_control": {
            "commander",
            "control_allocator",
            "mc_rate_control",
            "mc_att_control",
            "mc_hover_thrust_estimator",
            "flight_mode_manager",
            "mc_pos_control",
        },
    }
