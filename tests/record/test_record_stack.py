"""Recording real stacks and replaying recordings into stacks of their own (processes, loopback only, headless)."""

import csv
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import time

import msgspec

from stack.bus.node import stable_publisher_id
from stack.bus.topics import HEADER
from stack.msg.sensors import SensorGyro
from stack.msg.setpoints import TrajectorySetpoint, VehicleRatesSetpoint
from stack.record.recorder import RecordingError, RecordingInfo, RecordingReader, RecordingWriter
from tests.support.harness import (
    REPO,
    RunningStack,
    chain_profile,
    eventually,
    launch_profile,
    stack_env,
    wait_no_processes,
)

STEPS = 1500
NEG_NAN = math.copysign(math.nan, -1.0)
CHAIN_PUBLISHERS = {
    "sensor_gyro": "tick_source",
    "vehicle_angular_velocity": "doubler",
    "vehicle_torque_setpoint": "summer",
    "vehicle_rates_setpoint": "pacer",
}


def recorder(path, **args) -> str:
    values = ", ".join(f"{k} = {json.dumps(str(v))}" for k, v in {"path": path, **args}.items())
    return f'\n[[module]]\nmodule = "recorder"\nargs = {{ {values} }}\n'


def log_cli(home, *args, timeout=120.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tests.record.logcli", *args],
        env=stack_env(home),
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=REPO,
    )


def by_channel(messages) -> dict[tuple[str, int, int], list]:
    out: dict[tuple[str, int, int], list] = {}
    for m in messages:
        out.setdefault((m.topic, m.instance, m.publisher_id), []).append(m)
    return out


def assert_nothing_lost(messages) -> None:
    """Every publisher numbers its messages per topic from 1: a complete recording has no gap."""
    for channel, ms in by_channel(messages).items():
        assert [m.index for m in ms] == list(range(1, len(ms) + 1)), channel


def test_a_lockstep_run_is_recorded_completely_and_exactly(tmp_path):
    home = tmp_path / "home"
    mcap, trace = tmp_path / "chain.mcap", tmp_path / "trace.json"
    profile = chain_profile(
        tmp_path / "chain.toml", tick_args=f'trace = "{trace}", steps = {STEPS}', extra=recorder(mcap)
    )
    stack = RunningStack(home, profile)
    try:
        assert stack.wait(timeout=180) == 0, stack.output
    finally:
        stack.kill()
    assert not wait_no_processes(home)
    assert f"recording finished: {3 * STEPS + STEPS // 5 + 1} messages" in stack.output

    with RecordingReader(mcap) as reader:
        assert reader.complete and reader.warnings == []
        info = reader.info
        assert (info.vehicle, info.profile, info.seed, info.lockstep) == ("t1", "chain", 7, True)
        messages = list(reader.iter_messages())
    topics = {t: [m for m in messages if m.topic == t] for t in CHAIN_PUBLISHERS}
    # The coordinator published STEPS gyros; the chain answered each; the 50 Hz pacer ticked 1 + STEPS/5 times.
    assert {t: len(ms) for t, ms in topics.items()} == {
        "sensor_gyro": STEPS,
        "vehicle_angular_velocity": STEPS,
        "vehicle_torque_setpoint": STEPS,
        "vehicle_rates_setpoint": STEPS // 5 + 1,
    }
    assert len(messages) == sum(len(ms) for ms in topics.values())
    assert_nothing_lost(messages)
    for topic, module in CHAIN_PUBLISHERS.items():
        assert {m.publisher_id for m in topics[topic]} == {stable_publisher_id("t1", module)}
    assert all(m.lockstep_time for m in messages)
    logs = [m.log_time_us for m in messages]
    assert logs == sorted(logs) and logs[-1] == 4000 * STEPS

    # Exact values: the gyro is the seeded generator; the torque is what the coordinator traced.
    rng = random.Random(7)
    gyros = [m.msg for m in topics["sensor_gyro"]]
    for k, g in enumerate(gyros, 1):
        x = rng.uniform(-1.0, 1.0)
        assert (g.timestamp, g.x, g.y) == (4000 * k, x, 2.0 * x) and math.isnan(g.temperature)
    torques = [m.msg for m in topics["vehicle_torque_setpoint"]]
    rows = json.loads(trace.read_text())
    assert len(rows) == STEPS - 1
    for row, torque, next_gyro in zip(rows, torques, gyros[1:], strict=False):
        assert [row[0] - 4000, *row[1:]] == [torque.timestamp, *torque.xyz]
        assert next_gyro.z == torque.xyz[0]

    out = log_cli(home, "log", "info", str(mcap))
    assert out.returncode == 0, out.stderr
    assert "vehicle 't1', profile chain, seed 7 (lockstep, simulated time)" in out.stdout
    assert f"{3 * STEPS + STEPS // 5 + 1} messages on 4 topics" in out.stdout
    line = next(ln for ln in out.stdout.splitlines() if ln.startswith("vehicle_rates_setpoint"))
    assert line.split()[1:4] == ["0", "VehicleRatesSetpoint", str(STEPS // 5 + 1)]
    assert abs(float(line.split()[4]) - 50.0) < 0.5
    assert line.split()[5] == "pacer"  # the publisher by its module name
    assert "commit unknown" not in out.stdout
    as_json = json.loads(log_cli(home, "log", "info", str(mcap), "--json").stdout)
    assert as_json["message_count"] == len(messages) and as_json["complete"]
    by_topic = {t["topic"]: t["publishers"] for t in as_json["topics"]}
    assert by_topic["sensor_gyro"] == ["tick_source"] and by_topic["vehicle_torque_setpoint"] == ["summer"]

    out = log_cli(home, "log", "export", str(mcap), "--csv", str(tmp_path / "csv"), "--topics", "sensor_gyro")
    assert out.returncode == 0, out.stderr
    assert "wrote 1 CSV files (1500 rows)" in out.stdout
    with (tmp_path / "csv" / "sensor_gyro_0.csv").open(newline="") as f:
        table = list(csv.DictReader(f))
    assert [float(r["x"]) for r in table] == [g.x for g in gyros]


def replay_source(path) -> list:
    """A lockstep recording over 8 s with every kind of non-finite float and an undecoded payload."""
    with RecordingWriter(path, RecordingInfo(vehicle="t1", lockstep=True)) as w:
        for k in range(1, 201):
            t = 40_000 * k
            special = (math.nan, NEG_NAN, math.inf, -math.inf, 0.1 * k)[k % 5]
            w.write("sensor_gyro", 0, SensorGyro(timestamp=t, x=special, y=-special, z=k), 0x11, k, t, 1, t)
            if k % 4 == 0:
                sp = TrajectorySetpoint(timestamp=t, position=(special, 1.0, NEG_NAN), yaw=math.inf)
                w.write("trajectory_setpoint", 0, sp, 0x22, k // 4, t, 1, t)
            if k % 50 == 0:
                w.write("vehicle_rates_setpoint", 2, VehicleRatesSetpoint(roll=special), 0x33, k // 50, t, 0, t)
                w.write_raw("mystery", 0, b"\x92\xa3abc\x01", 0xFEED, 0x44, k // 50, t, 1, t, "unknown topic")
    with RecordingReader(path) as reader:
        return list(reader.iter_messages())


def start_replay(home, *args) -> tuple[subprocess.Popen[str], str]:
    """`stack replay ARGS` in the background, and the name of the stack it replays into."""
    replay = subprocess.Popen(
        [sys.executable, "-m", "tests.record.logcli", "replay", *args],
        env=stack_env(home),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    assert replay.stdout is not None
    first = replay.stdout.readline()
    found = re.match(r"\[stack\] replay '(\S+)' \(another terminal attaches with --vehicle \1\)$", first)
    assert found, first
    return replay, found.group(1)


def test_replay_republishes_exactly_what_was_recorded(tmp_path):
    home = tmp_path / "home"
    source = tmp_path / "source.mcap"
    recorded = replay_source(source)
    replay, name = start_replay(home, str(source), "--speed", "4", "--wait-subscribers", "60")
    listener = None
    try:
        assert name == f"t1-replay-{replay.pid}"
        out_file = tmp_path / "heard.msgpack"
        # The replay is the only stack of this home: the listener finds it unnamed.
        listener = subprocess.Popen(
            [sys.executable, "-m", "tests.record.listener", str(len(recorded)), str(out_file)],
            env=stack_env(home),
            stdout=subprocess.PIPE,
            text=True,
            cwd=REPO,
        )
        assert listener.stdout is not None and listener.stdout.readline().strip() == "ready"
        start = time.monotonic()
        stdout, stderr = replay.communicate(timeout=120)
        elapsed = time.monotonic() - start
        assert replay.returncode == 0, stderr
        assert f"replayed {len(recorded)} messages" in stdout
        assert listener.wait(timeout=60) == 0
    finally:
        for proc in (listener, replay):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait()
    assert not list((home / "state").glob("*.json"))
    assert elapsed >= 8.0 / 4 - 0.5  # paced by the recording's clock at 4x

    heard = msgspec.msgpack.decode(out_file.read_bytes())
    assert len(heard) == len(recorded)
    publishers = set()
    index: dict[str, int] = {}
    for seq, ((key, attachment, payload), m) in enumerate(zip(heard, recorded, strict=True), 1):
        assert key == f"stack/t1/{m.topic}/{m.instance}"
        assert payload == m.wire_payload()  # byte for byte: NaN signs and infinities included
        fp, publisher, sequence, idx, pub_time, flags, _run = HEADER.unpack(attachment)
        assert (fp, pub_time, flags) == (m.fingerprint, m.pub_time_us, m.flags)
        assert sequence == seq
        index[key] = index.get(key, 0) + 1
        assert idx == index[key]
        publishers.add(publisher)
    assert len(publishers) == 1 and publishers.isdisjoint({0x11, 0x22, 0x33, 0x44})
    first, second = (msgspec.msgpack.decode(h[2], type=SensorGyro) for h in heard[:2])
    assert math.copysign(1.0, first.x) < 0 < math.copysign(1.0, first.y) and math.isnan(first.x)
    assert (second.x, second.y) == (math.inf, -math.inf)


def test_a_killed_recorder_leaves_a_readable_file_and_the_flight_goes_on(tmp_path):
    home = tmp_path / "home"
    mcap = tmp_path / "killed.mcap"
    stack = RunningStack(home, chain_profile(tmp_path / "chain.toml", extra=recorder(mcap)))
    try:
        stack.wait_up()
        stack.wait_for(r"lockstep starting")

        def sim_time() -> int:
            return max(m.get("sim_time_us", 0) for m in stack.status()["modules"])

        def recorded() -> int:  # messages in the closed chunks
            try:
                with RecordingReader(mcap) as reader:
                    return sum(1 for _ in reader.iter_messages())
            except (OSError, RecordingError):  # not there yet, or not even its header
                return 0

        eventually(lambda: recorded() > 1000, what="a thousand messages recorded")
        os.kill(stack.module_pids()["recorder"], signal.SIGKILL)
        stack.wait_for(r"recorder failed with exit code -9")
        t1 = sim_time()
        eventually(lambda: sim_time() > t1 + 500_000, what="the flight going on without its recorder")
    finally:
        stack.stop()
    assert not wait_no_processes(home)
    with RecordingReader(mcap) as reader:
        assert not reader.complete
        messages = list(reader.iter_messages())
        assert any("incomplete recording" in w for w in reader.warnings)
    assert len(messages) > 1000
    assert_nothing_lost(messages)
    out = log_cli(home, "log", "info", str(mcap))
    assert out.returncode == 0 and "INCOMPLETE" in out.stdout and "warning:" in out.stderr


def test_refused_files_give_one_clear_line(tmp_path):
    bad = tmp_path / "random.mcap"
    bad.write_bytes(random.Random(3).randbytes(5000))
    for args in (("log", "info", str(bad)), ("log", "export", str(bad), "--csv", str(tmp_path)), ("replay", str(bad))):
        out = log_cli(tmp_path, *args)
        assert out.returncode == 1
        assert out.stderr.strip() == f"error: {bad}: not an MCAP file (it does not start with the MCAP magic bytes)"


def test_the_flight_stack_is_recorded_without_loss_and_exports(tmp_path):
    home = tmp_path / "home"
    mcap = tmp_path / "flight.mcap"
    profile = launch_profile(tmp_path, "sitl_quad", recorder(mcap))
    stack = RunningStack(home, profile, "--quiet")
    try:
        stack.wait_up()
        # the attitude estimate starts once the estimator has converged, about two simulated seconds in
        sim_time = lambda: max(m.get("sim_time_us", 0) for m in stack.status()["modules"])  # noqa: E731
        eventually(lambda: sim_time() > 3_500_000, 180.0, "three and a half simulated seconds")
        assert stack.stop(signal.SIGTERM) == 0, stack.output
    finally:
        stack.kill()
    assert not wait_no_processes(home)
    with RecordingReader(mcap) as reader:
        assert reader.complete and reader.warnings == []
        assert (reader.info.vehicle, reader.info.profile, reader.info.lockstep) == ("v1", "sitl_quad", True)
        assert all(c.decodable for c in reader.channels())
        messages = list(reader.iter_messages())
    assert_nothing_lost(messages)
    counts = {t: sum(1 for m in messages if m.topic == t) for t in ("sensor_gyro", "vehicle_attitude")}
    assert min(counts.values()) > 250  # over a simulated second of the 250 Hz loop
    assert all(m.lockstep_time and m.msg is not None for m in messages)

    out = log_cli(home, "log", "export", str(mcap), "--csv", str(tmp_path / "csv"), "--rrd", str(tmp_path / "f.rrd"))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "f.rrd").stat().st_size > 0 and (tmp_path / "csv" / "vehicle_attitude_0.csv").exists()


def test_a_replay_is_a_stack_of_its_own_beside_a_live_lockstep_stack(tmp_path):
    home = tmp_path / "home"
    source = tmp_path / "source.mcap"
    replay_source(source)  # vehicle t1, lockstep times, as the live stack
    live = RunningStack(home, chain_profile(tmp_path / "chain.toml"))
    replay = None
    try:
        live.wait_up()
        live.wait_for(r"lockstep starting")
        replay, name = start_replay(home, str(source), "--loop", "--speed", "4")
        before = max(m.get("sim_time_us", 0) for m in live.status()["modules"])
        out = live.cli("status", "--vehicle", name, "--json")
        assert out.returncode == 0, out.stderr
        assert json.loads(out.stdout) == {
            "vehicle": "t1",
            "host": "local",
            "hosts": ["local"],
            "silent_hosts": [],
            "lost_hosts": {},
            "denied": {},
            "profile": "replay of source.mcap",
            "lockstep": True,
            "modules": [],
        }
        echo = ("topic", "echo", "trajectory_setpoint", "-n", "1", "--json")  # recorded, and not in the chain
        out = live.cli(*echo, "--vehicle", name, "--timeout", "30")
        assert out.returncode == 0, out.stderr
        assert json.loads(out.stdout)["position"][1] == 1.0
        out = live.cli(*echo, "--timeout", "3")  # unnamed: the `stack up` stack, which never sees the replay
        assert out.returncode == 1 and "without a message on trajectory_setpoint" in out.stderr
        plots = tmp_path / "replay.rrd"
        out = live.cli("plot", "--save", str(plots), "--duration", "8", "--vehicle", name)
        assert out.returncode == 0 and plots.stat().st_size > 0, out.stderr
        report = live.status()
        assert max(m.get("sim_time_us", 0) for m in report["modules"]) > before
        for m in report["modules"]:
            assert m["state"] == "running"
            assert (m["foreign"], m["decode_errors"], m["schema_errors"]) == (0, 0, 0), m
        out = live.cli("down", "--vehicle", name)
        assert out.returncode == 0, out.stderr
        stdout, stderr = replay.communicate(timeout=30)
        assert replay.returncode == 0 and "interrupted" in stderr and "replayed" in stdout
        assert live.proc.poll() is None
    finally:
        if replay is not None and replay.poll() is None:
            replay.kill()
            replay.wait()
        assert live.stop() == 0
    assert not wait_no_processes(home)
