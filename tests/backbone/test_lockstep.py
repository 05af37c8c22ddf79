"""Lockstep: time advances only when triggered work is done; runs are deterministic; stalls are named."""

import json
import os
import signal
import subprocess
import time

from tests.support.harness import RunningStack, chain_profile, wait_no_processes

STEPS = 3000


def run_chain(tmp_path, name: str, seed: int = 7, load: bool = False) -> list:
    home = tmp_path / f"home-{name}"
    trace = tmp_path / f"{name}.json"
    probe = tmp_path / f"{name}-probe.json"
    profile = chain_profile(
        tmp_path / f"{name}.toml",
        seed=seed,
        tick_args=f'trace = "{trace}", steps = {STEPS}',
        extra=f'[[module]]\nmodule = "tests.support.modules:Probe"\nargs = {{ out = "{probe}" }}\n',
    )
    hogs = [subprocess.Popen(["python3", "-c", "while True: pass"]) for _ in range(2)] if load else []
    try:
        stack = RunningStack(home, profile)
        code = stack.wait(timeout=300)
    finally:
        for h in hogs:
            h.kill()
            h.wait()
    assert code == 0, stack.output
    assert "critical module tick_source exited" in stack.output
    assert not wait_no_processes(home)
    return json.loads(trace.read_text()), json.loads(probe.read_text())


def test_lockstep_is_deterministic_whatever_the_scheduling(tmp_path):
    trace_a, probe_a = run_chain(tmp_path, "a")
    trace_b, probe_b = run_chain(tmp_path, "b", load=True)
    assert len(trace_a) == STEPS - 1
    assert trace_a == trace_b
    assert probe_a[: STEPS - 1] == probe_b[: STEPS - 1]
    trace_c, _ = run_chain(tmp_path, "c", seed=8)
    assert trace_c != trace_a

    # Time advanced in exact 4 ms steps, one torque per step, each computed from the previous step.
    times = [row[0] for row in trace_a]
    assert times == [8000 + 4000 * i for i in range(STEPS - 1)]
    # dt comes from timestamp_sample, clamped: the first run gets the 20 ms maximum.
    assert trace_a[0][3] == 0.02 and {row[3] for row in trace_a[1:]} == {0.004}

    # What a triggered module sees at time t: the coordinator's trigger, the doubler's output of the
    # previous step (same-step output of another module waits) and the pacer's latest tick before t.
    # The 50 Hz pacer ticks on the first step, then on every 20 ms boundary.
    for now, sample, sp_time, av_time, dt in probe_a[1 : STEPS - 1]:
        assert now == sample
        assert av_time == now - 4000
        assert sp_time == max(4000, ((now - 1) // 20000) * 20000)
        assert dt == 0.004


def test_a_member_that_dies_is_named_and_the_rest_go_on(tmp_path):
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml"))
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep starting")
        pids = stack.module_pids()
        time.sleep(1.0)
        os.kill(pids["pacer"], signal.SIGKILL)
        stack.wait_for(r"lockstep member pacer left at t=", timeout=30)
        stack.wait_for(r"pacer failed with exit code -9")
        t1 = max(m["sim_time_us"] for m in stack.status()["modules"])
        time.sleep(2.0)
        t2 = max(m["sim_time_us"] for m in stack.status()["modules"])
        assert t2 > t1
    finally:
        assert stack.stop() == 1
    assert not wait_no_processes(home)


def test_a_stalled_member_is_named_and_the_stack_stops(tmp_path):
    home = tmp_path / "home"
    profile = chain_profile(
        tmp_path / "chain.toml",
        extra='[[module]]\nmodule = "tests.support.modules:Staller"\nargs = { stall_at = 300 }\n',
    )
    stack = RunningStack(home, profile)
    code = stack.wait(timeout=120)
    assert code == 1
    stack_line = stack.wait_for(r"lockstep stalled at t=([\d.]+) s: no progress for 4 s, waiting for (.*)$")
    assert stack_line.group(2) == "staller (sensor_gyro/0)"
    assert abs(float(stack_line.group(1)) - 300 * 0.004) < 1e-6
    assert "critical module tick_source failed" in stack.output
    assert not wait_no_processes(home)
