"""The rerun_bridge module in real test stacks, and `stack plot` attached to one. Loopback only, no viewer."""

import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import psutil

from stack.record.recorder import RecordingReader
from stack.viz import layout as lay
from stack.viz.export import export_rrd
from tests.support.harness import (
    REPO,
    RunningStack,
    chain_profile,
    cli_in_its_own_session,
    eventually,
    run_cli,
    stack_env,
    wait_no_processes,
)
from tests.viz.rrd import read_rrd

STEPS = 1000


def bridge(name: str, **args: object) -> str:
    """A [[module]] entry for a rerun_bridge named ``name`` (JSON scalars are valid TOML values)."""
    values = ", ".join(f"{k} = {json.dumps(v)}" for k, v in args.items())
    return f'\n[[module]]\nname = "{name}"\nmodule = "rerun_bridge"\nargs = {{ {values} }}\n'


def test_lockstep_flight_plotted_live_recorded_and_exported_with_the_same_layout(tmp_path):
    home = tmp_path / "home"
    full, decimated, tiny, mcap = (tmp_path / n for n in ("full.rrd", "50hz.rrd", "tiny.rrd", "flight.mcap"))
    extra = (
        f'\n[[module]]\nmodule = "recorder"\nargs = {{ path = "{mcap}" }}\n'
        + bridge("plots", save=str(full), spawn=False, plot_rate_hz=0.0)
        + bridge("plots_50hz", save=str(decimated), spawn=False)
        + bridge("tiny", save=str(tiny), spawn=False, plot_rate_hz=0.0, queue=16)
    )
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", tick_args=f"steps = {STEPS}", extra=extra))
    try:
        assert stack.wait(timeout=180) == 0
    finally:
        stack.kill()
    assert not wait_no_processes(home)
    output = stack.output

    live = read_rrd(full)
    estimate = lay.rates_path("roll", lay.ESTIMATE)
    said = re.search(r"\[plots\] INFO\s+plotted \d+ of \d+ messages .*; 0 buffer overruns, (\d+) samples lost", output)
    assert said, output
    lost = int(said.group(1))
    every_step = [4000 * k for k in range(1, STEPS + 1)]
    if lost == 0:
        assert live.times(estimate) == every_step  # every step, in order
        assert live.rows(lay.TORQUE) == STEPS
    else:  # a machine so loaded that the passive bridge was lapped: it said how much it lost, the rest is in order
        times = live.times(estimate)  # what was lost may have been other topics' samples only
        assert times == sorted(set(times)) and set(times) <= set(every_step) and STEPS - len(times) <= lost
        assert re.search(r"\[plots\] WARNING fell behind the flight: \d+ samples lost before they were read", output)
    if lost == 0:
        assert live.rows(lay.rates_path("yaw", lay.SETPOINT)) == STEPS // 5 + 1  # the 50 Hz pacer
    assert live.rows(lay.VEHICLE_ARMS) == 0 and lay.VEHICLE_ARMS in live.static
    assert live.blueprints

    fifty = read_rrd(decimated)
    buckets = len({4000 * k // 20000 for k in range(1, STEPS + 1)})  # one row per 20 ms of the vehicle's time
    overruns = re.search(r"\[plots_50hz\] INFO\s+plotted \d+ of \d+ messages .*; (\d+) buffer overruns, (\d+)", output)
    assert overruns, output
    if overruns.group(1) == overruns.group(2) == "0":
        assert fifty.rows(estimate) == buckets
    else:  # a machine so loaded that the passive bridge was lapped: what it lost, it said
        assert 0 < fifty.rows(estimate) <= buckets  # lapped between buckets, it can still fill each one

    # A bridge that cannot keep up drops its oldest samples and says so; the flight is not slowed.
    assert re.search(r"\[tiny\] WARNING vehicle_\w+: ring buffer of 16 full, oldest samples dropped", output)
    assert read_rrd(tiny).rows(estimate) < STEPS

    exported = tmp_path / "exported.rrd"
    with RecordingReader(mcap) as reader:
        export_rrd(reader, exported)
    replay = read_rrd(exported)
    assert replay.entities() == live.entities()
    for entity in live.entities():
        if lost == 0:
            assert replay.temporal[entity] == live.temporal[entity], entity
        else:  # the recording (lossless) has every row the bridge plotted
            assert set(live.times(entity)) <= set(replay.times(entity)), entity


def test_a_bridge_that_falls_behind_a_lockstep_flight_says_what_it_lost_and_does_not_slow_it(tmp_path):
    home = tmp_path / "home"
    extra = bridge("plots", save=str(tmp_path / "plots.rrd"), spawn=False, plot_rate_hz=0.0)
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", tick_args="steps = 25000", extra=extra))

    def sim_time_us() -> int:
        return max(m.get("sim_time_us", 0) for m in stack.status()["modules"])

    try:
        stack.wait_up()
        bridge_pid = stack.module_pids()["plots"]
        os.kill(bridge_pid, signal.SIGSTOP)
        try:
            stopped_at = sim_time_us()
            # Two seconds of the flight are 500 records of each 250 Hz topic: more than a ring holds.
            eventually(lambda: sim_time_us() > stopped_at + 2_000_000, what="two seconds of flight")
        finally:
            os.kill(bridge_pid, signal.SIGCONT)
        assert stack.wait(timeout=180) == 0
    finally:
        stack.kill()
    said = re.search(
        r"\[plots\] INFO\s+plotted \d+ of \d+ messages .*; \d+ buffer overruns, (\d+) samples lost", stack.output
    )
    assert said and int(said.group(1)) > 0, stack.output
    assert re.search(r"\[plots\] WARNING fell behind the flight: \d+ samples lost before they were read", stack.output)


def listening_and_remote(proc: psutil.Process) -> tuple[set[str], set[str]]:
    listen, remote = set(), set()
    for c in proc.net_connections("inet"):
        if c.status == psutil.CONN_LISTEN:
            listen.add(c.laddr.ip)
        elif c.raddr:
            remote.add(c.raddr.ip)
    return listen, remote


def test_web_viewer_listens_on_loopback_only_and_stops_with_the_bridge(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.delenv("CI", raising=False)
    home = tmp_path / "home"
    extra = bridge("web_plots", web=True, grpc_port=0, web_port=0) + bridge("idle", spawn=False)
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False, extra=extra))
    try:
        url = stack.wait_for(r"\[web_plots\] INFO\s+web viewer: (http://127\.0\.0\.1:\d+/\?url=\S+)").group(1)
        stack.wait_up()
        assert "rerun%2Bhttp%3A%2F%2F127.0.0.1%3A" in url
        # Said again once the stack is up, as the supervisor's last start-up line, where it is seen.
        said = stack.wait_for(r"\[stack\] web_plots web viewer: (\S+)  <- open it in a browser")
        assert said.group(1) == url
        up = next(i for i, line in enumerate(stack.lines) if re.search(r"\[stack\] all \d+ modules up", line))
        assert stack.lines.index(said.string) > up
        pid = stack.module_pids()["web_plots"]
        bridge_proc = psutil.Process(pid)
        servers = bridge_proc.children(recursive=True)
        assert len(servers) == 1
        server = servers[0]
        assert server.environ().get("CI") == "1"  # Rerun's analytics off for the processes we start
        with urllib.request.urlopen(url.split("?")[0], timeout=10) as page:
            assert page.status == 200
        time.sleep(0.5)
        for proc in (bridge_proc, server):
            listen, remote = listening_and_remote(proc)
            assert listen and listen <= {"127.0.0.1"}, (proc.name(), listen)
            assert remote <= {"127.0.0.1"}, (proc.name(), remote)
        assert "[idle] WARNING nothing to plot to" in stack.output
    finally:
        code = stack.stop()
    assert code == 0
    assert not psutil.pid_exists(server.pid) or server.status() == psutil.STATUS_ZOMBIE
    assert not wait_no_processes(home)


def test_stack_plot_attaches_to_a_running_stack(tmp_path):
    home = tmp_path / "home"
    out = tmp_path / "attached.rrd"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml"))
    try:
        stack.wait_up()
        cli = "import typer; from stack.cli.plot import plot; app = typer.Typer(); app.command()(plot); app()"

        def plot(save: Path, duration: str) -> subprocess.CompletedProcess[str]:
            args = [sys.executable, "-c", cli, "--save", str(save), "--duration", duration]
            return subprocess.run(args, env=stack_env(home), capture_output=True, text=True, timeout=60, cwd=REPO)

        result = plot(out, "3")
        assert result.returncode == 0, result.stderr
        assert "saving plots to" in result.stdout and "plot stopped" in result.stdout
        # --duration counts from when plotting starts, however long setting up Rerun takes on a loaded machine.
        brief = tmp_path / "brief.rrd"
        result = plot(brief, "0.01")
        assert result.returncode == 0 and "saving plots to" in result.stdout and brief.exists(), result
        assert stack.proc.poll() is None
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)
    rrd = read_rrd(out)
    times = rrd.times(lay.rates_path("roll", lay.ESTIMATE))
    assert len(times) >= 3  # how many depends on the machine's load: the stack runs as fast as it can
    # lockstep: sim_time is the simulated clock (4 ms steps), decimated to 50 Hz buckets
    assert all(t % 4000 == 0 for t in times)
    assert len({t // 20000 for t in times}) == len(times)


def test_ctrl_c_on_stack_plot_web_stops_it_quietly_with_its_server(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    home = tmp_path / "home"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", lockstep=False))
    try:
        stack.wait_up()
        # In a session of its own, as a terminal runs it: Ctrl-C signals the whole foreground process group.
        plot = cli_in_its_own_session(home, "plot", "--web")
        assert plot.stdout is not None
        try:
            for line in plot.stdout:
                if " ready " in line:
                    break
            server = psutil.Process(plot.pid).children(recursive=True)
            assert server, "no web viewer server"
            os.killpg(plot.pid, signal.SIGINT)
            out, err = plot.communicate(timeout=30)
        finally:
            if plot.poll() is None:  # never left running if the test fails
                os.killpg(plot.pid, signal.SIGKILL)
                plot.wait()
        assert plot.returncode == 0, err
        assert "plot stopped" in out
        assert "ERROR" not in err and "\x1b[" not in err, err  # nothing from Rerun about a severed connection
        assert not [p for p in server if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    finally:
        assert stack.stop() == 0
    assert not wait_no_processes(home)


def test_stack_plot_without_a_display_says_to_use_web_or_save(tmp_path, monkeypatch):
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    out = run_cli(tmp_path, "plot")
    assert out.returncode == 1
    assert out.stderr == (
        "error: no display here for the Rerun viewer: use --web (a viewer in the browser) or --save FILE.rrd\n"
    )
