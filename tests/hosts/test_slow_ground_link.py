"""Ground tools behind a slow link never slow the vehicle: in a real-time hover over three hosts, the ground host's
link limited to 512 kbit/s, with ``stack topic echo`` of the fastest topics running there. The gyro samples still
reach the flight-control host and the motor commands the simulator's host at their full rate with no stall (a
message that may not be dropped, queued behind telemetry for the ground, used to hold up the simulator's router for
5 s and the vehicle landed on a lost host); the ground receives less, but what it receives is recent."""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
from pathlib import Path

import pytest

from tests.hosts.split import TAKEOFF_TIMEOUT_S, split_profile, take_off
from tests.hosts.split import stack_on as stack
from tests.hosts.test_host_loss import truth
from tests.hosts.test_vehicle_across_hosts import HOSTS, START_TIMEOUT_S, bring_up, running, status
from tests.support.harness import REPO, eventually, stack_env
from tests.support.hosts import Host

pytestmark = [pytest.mark.timeout(500), pytest.mark.xdist_group("heavy_wall_clock")]

MEASURE_S = 12
SLOW_LINK = "512kbit"
ECHOED = ("sensor_gyro", "sensor_accel", "vehicle_attitude", "actuator_motors")
"""Topics at 250 Hz from each flight host: their echoes want about 1 Mbit/s, twice what the link carries."""


def measure(host: Host, topic: str, seconds: float, log: Path) -> subprocess.Popen[str]:
    """tests/hosts/arrivals.py on ``host``: a JSON line of figures per second into ``log``."""
    return host.popen(
        sys.executable, "-m", "tests.hosts.arrivals", topic, str(seconds),
        env=stack_env(host.home), stdout=log.open("w"), stderr=subprocess.STDOUT, cwd=REPO,
    )  # fmt: skip


def figures(probe: subprocess.Popen[str], log: Path) -> list[dict]:
    assert probe.wait(timeout=120) == 0, log.read_text()
    return [json.loads(line) for line in log.read_text().splitlines()]


def link_full(ground: Host, full_rate: float, log: Path) -> bool:
    """Whether the ground now receives the gyro at under 0.8 of its full rate: the tools subscribed, and the
    telemetry they asked for fills the link."""
    windows = figures(measure(ground, "sensor_gyro", 2, log), log)
    return sum(w["received"] for w in windows) < 0.8 * full_rate * len(windows)


def ground_tool(ground: Host, *args: str, log: Path) -> subprocess.Popen[str]:
    """A ``stack`` command on the ground host, at the lowest CPU priority: the test's hosts share two cores, and the
    point is the link, not the CPU (the tools starting beside the hosts' routers, at their weight, delayed the gyro
    and the motor commands between the hosts and the hover tumbled)."""
    return ground.popen(
        sys.executable, "-m", "stack", *args,
        env=stack_env(ground.home), niceness=19, stdout=subprocess.DEVNULL, stderr=log.open("w"), cwd=REPO,
    )  # fmt: skip


def estimate_and_setpoint(control: Host) -> str:
    """The height estimate, the position controller's setpoint and the hover thrust estimate, for a failure's message:
    they tell an estimate gone wrong from a control that could not hold it."""
    fields = {
        "vehicle_local_position": ("x", "y", "z", "vz"),
        "vehicle_local_position_setpoint": ("z", "vz", "thrust"),
        "hover_thrust_estimate": ("hover_thrust", "valid"),
    }
    said = []
    for topic, names in fields.items():
        out = stack(control, "topic", "echo", topic, "-n", "1", "--json", timeout=60.0)
        msg = json.loads(out.stdout) if out.returncode == 0 else {}
        said.append(f"{topic}: {({n: msg.get(n) for n in names}) if msg else out.stderr.strip()}")
    return "; ".join(said)


def test_a_ground_host_behind_a_slow_link_never_slows_the_vehicle(network, tmp_path: Path) -> None:
    net = network(HOSTS)
    sim, control, ground = (net.hosts[h] for h in HOSTS)
    profile = split_profile(tmp_path / "split.toml", net)
    procs = bring_up(net, list(HOSTS), profile, tmp_path, "--realtime")
    logs = lambda: "\n".join(p.read_text() for p in tmp_path.glob("*.log"))  # noqa: E731
    eventually(lambda: running(status(ground), 12), START_TIMEOUT_S, "the vehicle up on all hosts")
    eventually(lambda: take_off(ground, 3), TAKEOFF_TIMEOUT_S, "a takeoff accepted and complete")

    listed = stack(ground, "topic", "list", "--json")
    assert listed.returncode == 0, listed.stdout + listed.stderr
    published = {row["topic"] for row in json.loads(listed.stdout) if row["publishers"]}
    assert published.issuperset(ECHOED), published
    baseline = measure(control, "sensor_gyro", 5, tmp_path / "baseline.jsonl")
    full_rate = statistics.median(w["received"] for w in figures(baseline, tmp_path / "baseline.jsonl"))

    ground.limit_rate(SLOW_LINK)
    # Each topic the ground reads costs the other hosts' routers a forward per message, whether the link takes it or
    # drops it: the three hosts here share two cores, which the vehicle's real-time stacks take most of. With a plot
    # (every topic) and an echo of each topic at 50 Hz or more, the routers' forwards starved the control loops
    # between the hosts and the hover tumbled; without the limit too, so the CPU, not the link. A few fast topics
    # fill a slower link as well.
    tools = [
        ground_tool(ground, "topic", "echo", topic, "--json", "--timeout", "600", log=tmp_path / f"echo-{topic}.err")
        for topic in ECHOED
    ]
    eventually(lambda: link_full(ground, full_rate, tmp_path / "filling.jsonl"), 60, "the link to the ground full")
    probes = {
        "gyro on the control host": (control, "sensor_gyro", "gyro"),
        "motors on the simulator's host": (sim, "actuator_motors", "motors"),
        "gyro on the ground host": (ground, "sensor_gyro", "ground"),
    }
    logs_of = {what: tmp_path / f"{name}.jsonl" for what, (_, _, name) in probes.items()}
    started = {what: measure(h, topic, MEASURE_S, logs_of[what]) for what, (h, topic, _) in probes.items()}
    seen = {what: figures(probe, logs_of[what]) for what, probe in started.items()}
    running_tools = [t for t in tools if t.poll() is None]
    for t in tools:
        t.terminate()
    for t in tools:
        t.wait(timeout=60)
    print(f"gyro at full rate on the control host: {full_rate} per s")
    for what, windows in seen.items():
        received = [w["received"] for w in windows]
        print(
            f"{what}: {min(received)}..{max(received)} per s, longest gap {max(w['gap_max_s'] for w in windows):.3f} s,"
            f" age p50 {statistics.median(w['age_p50_s'] for w in windows):.3f} s,"
            f" p99 {max(w['age_p99_s'] for w in windows):.3f} s"
        )
    assert len(running_tools) == len(tools), "a ground tool stopped:\n" + logs()

    # Margins for a loaded two-core machine, where other tests starve these processes now and then (measured on an
    # idle one: longest gap 0.03-0.12 s, age p99 under 0.09 s; beside other tests: gaps up to 0.36 s); the fault
    # they catch held every message of the simulator's host for 5 s (its gaps; a rate of 0.8 of the full one was
    # missed by 16 messages in 2400 once, in the full suite).
    for what in ("gyro on the control host", "motors on the simulator's host"):
        windows = seen[what]
        assert sum(w["received"] for w in windows) > 0.6 * full_rate * len(windows), (what, windows)
        assert max(w["gap_max_s"] for w in windows) < 2.0, (what, windows)
        assert max(w["age_p99_s"] for w in windows) < 2.0, (what, windows)
    ground_windows = seen["gyro on the ground host"]
    assert sum(w["received"] for w in ground_windows) < 0.8 * full_rate * len(ground_windows)  # telemetry dropped
    assert statistics.median(w["age_p50_s"] for w in ground_windows) < 1.0  # what arrives is recent, not queued

    hover = status(control)
    assert hover is not None
    summary, lost = hover["vehicle_summary"], hover["lost_hosts"]
    assert summary["armed"] and lost == {}, (summary, lost)
    altitude, _ = truth(sim)
    assert altitude > 2.0, f"at {altitude:.2f} m, {hover['vehicle_summary']}; {estimate_and_setpoint(control)}"
    assert "Lost host" not in (tmp_path / "sim.log").read_text() + (tmp_path / "control.log").read_text()
    land = stack(ground, "cmd", "land", "--wait")  # over the slow link
    assert land.returncode == 0 and "landed and disarmed" in land.stdout, land.stdout + land.stderr + logs()

    assert stack(ground, "down").returncode == 0
    codes = {name: p.wait(timeout=60) for name, p in procs.items()}
    assert codes == dict.fromkeys(HOSTS, 0), f"{codes}\n{logs()}"
