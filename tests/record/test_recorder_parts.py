"""The recorder's pieces without a bus: sample handling, topic selection, replay pacing, provenance."""

import logging
import math
import time

import msgspec
import pytest

from stack.bus.topics import FLAG_PROBE, HEADER
from stack.msg.registry import fingerprint
from stack.msg.sensors import SensorGyro
from stack.record.module import RecordingPump, SampleRecorder, profile_name
from stack.record.provenance import git_commit
from stack.record.recorder import RecordingInfo, RecordingReader, RecordingWriter
from stack.record.selection import TopicSelection
from stack.runtime.pacing import Pacer, parse_speed
from stack.supervisor.state import write_state


class Bytes:
    def __init__(self, data: bytes) -> None:
        self._data = data

    def to_bytes(self) -> bytes:
        return self._data


class FakeSample:
    """What SampleRecorder reads from a zenoh.Sample."""

    def __init__(self, key: str, payload: bytes, header: bytes | None) -> None:
        self.key_expr = key
        self.payload = Bytes(payload)
        self.attachment = Bytes(header) if header is not None else None


def header(fp: int, publisher: int, index: int, t: int, flags: int = 1) -> bytes:
    return HEADER.pack(fp, publisher, 1000 + index, index, t, flags, 0)


GYRO_FP = fingerprint(SensorGyro)


def record(tmp_path, samples, selection=(), lockstep=True, clock=lambda: 777):
    path = tmp_path / "r.mcap"
    with RecordingWriter(path, RecordingInfo(lockstep=lockstep)) as w:
        sink = SampleRecorder(w, TopicSelection(selection), lockstep, clock)
        for s in samples:
            sink.handle(s)
    with RecordingReader(path) as reader:
        return sink, list(reader.iter_messages()), {(c.topic, c.instance): c for c in reader.channels()}


def test_samples_become_exact_records_with_the_lockstep_clock(tmp_path):
    gyro = SensorGyro(timestamp=8000, x=math.nan)
    payload = msgspec.msgpack.encode(gyro)
    samples = [
        FakeSample("stack/v1/sensor_gyro/0", payload, header(GYRO_FP, 5, 1, 8000)),
        # Not lockstep time (a CLI command's wall clock): logged at the simulated time reached so far.
        FakeSample("stack/v1/sensor_gyro/0", payload, header(GYRO_FP, 6, 1, 10**12, flags=0)),
        FakeSample("stack/v1/sensor_gyro/0", payload, header(GYRO_FP, 5, 2, 4000)),
        FakeSample("stack/v1/sensor_gyro/0", payload, None),
        FakeSample("stack/v1/sensor_gyro/0", payload, b"short"),
        FakeSample("stack/v1/sensor_gyro/0", b"", HEADER.pack(GYRO_FP, 9, 0, 0, 0, FLAG_PROBE, 0)),
    ]
    sink, got, _ = record(tmp_path, samples)
    assert sink.without_header == 2
    assert [(m.publisher_id, m.index, m.pub_time_us, m.log_time_us, m.flags) for m in got] == [
        (5, 1, 8000, 8000, 1),
        (6, 1, 10**12, 8000, 0),
        (5, 2, 4000, 8000, 1),
    ]
    assert all(msgspec.msgpack.encode(m.msg) == payload for m in got)


def test_real_time_log_times_come_from_the_wall_clock(tmp_path):
    payload = msgspec.msgpack.encode(SensorGyro())
    _, got, _ = record(
        tmp_path, [FakeSample("stack/v1/sensor_gyro/0", payload, header(GYRO_FP, 5, 1, 3, 0))], lockstep=False
    )
    assert got[0].log_time_us == 777 and got[0].pub_time_us == 3


def test_foreign_and_malformed_payloads_are_kept_verbatim(tmp_path):
    samples = [
        FakeSample("stack/v1/sensor_gyro/0", b"\xc1broken", header(GYRO_FP, 5, 1, 10)),
        FakeSample("stack/v1/sensor_gyro/1", b"\x91\x01", header(GYRO_FP ^ 1, 5, 1, 20)),
        FakeSample("stack/v1/new_topic/0", b"\x92\x01\x02", header(42, 7, 1, 30)),
    ]
    sink, got, channels = record(tmp_path, samples)
    assert [(m.topic, m.instance, m.payload, m.fingerprint) for m in got] == [
        ("sensor_gyro", 0, b"\xc1broken", GYRO_FP),
        ("sensor_gyro", 1, b"\x91\x01", GYRO_FP ^ 1),
        ("new_topic", 0, b"\x92\x01\x02", 42),
    ]
    assert channels[("sensor_gyro", 0)].raw_reason.startswith("payload does not decode as SensorGyro")
    assert channels[("sensor_gyro", 1)].raw_reason.startswith("schema fingerprint differs")
    assert channels[("new_topic", 0)].raw_reason == "topic not in this build's catalogue"
    assert sink.writer.raw_messages == 3


def test_selection_and_non_topic_keys(tmp_path):
    payload = msgspec.msgpack.encode(SensorGyro())
    samples = [
        FakeSample(f"stack/v1/sensor_gyro/{i}", payload, header(GYRO_FP, 5, 1, 10 * i + 1)) for i in range(3)
    ] + [FakeSample("stack/v1/sensor_gyro/x", payload, header(GYRO_FP, 5, 1, 99))]
    _, got, _ = record(tmp_path, samples, selection=["sensor_gyro/1,sensor_gyro/2"])
    assert [m.instance for m in got] == [1, 2]


def test_topic_selection_parsing():
    s = TopicSelection(["a, b/2", "c"])
    assert ("a", 5) in s and ("b", 2) in s and ("b", 1) not in s and ("d", 0) not in s
    assert TopicSelection([""]).everything and ("x", 3) in TopicSelection()
    assert s.missing_from([("a", 0), ("b", 1)]) == ["c", "b/2"]
    with pytest.raises(ValueError, match="topic/instance"):
        TopicSelection(["a/b"])


def test_time_is_paced_by_its_stamps_over_the_speed_and_a_late_run_carries_on_from_where_it_is():
    now = [100.0]
    clock = Pacer(2.0, clock=lambda: now[0])
    assert clock.delay_s(5_000_000) == 0.0  # the first step or message goes at once
    assert clock.delay_s(6_000_000) == pytest.approx(0.5)
    now[0] += 0.2
    assert clock.delay_s(7_000_000) == pytest.approx(0.8)
    assert clock.delay_s(6_500_000) == pytest.approx(0.8)  # never earlier than its predecessor
    now[0] += 1.6  # 0.3 s late for 8 s (due at 101.5): within MAX_LAG_S, due at once
    assert clock.delay_s(8_000_000) == 0.0 and clock.behind == 0
    now[0] += 5.0
    assert clock.delay_s(8_100_000) == 0.0 and clock.behind == 1  # far behind: from here on at the same speed,
    assert clock.delay_s(9_100_000) == pytest.approx(0.5)  # not a burst of catching up
    clock.restart()
    assert clock.delay_s(1_000) == 0.0 and clock.delay_s(501_000) == pytest.approx(0.25)
    fast = Pacer(0.0, clock=lambda: now[0])
    assert fast.delay_s(0) == fast.delay_s(10**9) == 0.0
    slept: list[float] = []

    def sleep(seconds: float) -> None:
        slept.append(seconds)
        now[0] += seconds

    paced = Pacer(1.0, clock=lambda: now[0], sleep=sleep)
    paced.wait(0)
    paced.wait(4_000)
    paced.wait(4_100)  # due within MIN_SLEEP_S of the last: no sleep
    assert slept == [pytest.approx(0.004)]
    for bad in (-1.0, math.nan, math.inf):
        with pytest.raises(ValueError):
            Pacer(bad)


@pytest.mark.parametrize(
    ("text", "speed"), [("1", 1.0), ("2.5", 2.5), ("0.5", 0.5), ("max", 0.0), ("MAX", 0.0), ("0", 0.0)]
)
def test_a_speed_is_a_factor_or_max(text, speed):
    assert parse_speed(text) == speed


@pytest.mark.parametrize("text", ["-1", "nan", "inf", "fast", "", "1e400"])
def test_a_speed_that_is_not_a_factor_is_refused(text):
    with pytest.raises(ValueError, match="factor > 0"):
        parse_speed(text)


def test_git_commit_is_read_from_the_work_tree_else_from_the_build(tmp_path):
    sha = "0123456789abcdef0123456789abcdef01234567"
    built = tmp_path / "COMMIT"
    assert git_commit(tmp_path, built) == ""
    built.write_text("89abcdef" * 5 + "\n")  # an installed copy: what its build wrote
    assert git_commit(tmp_path, built) == "89abcdef" * 5
    built.write_text("not a sha\n")
    assert git_commit(tmp_path, built) == ""
    (tmp_path / ".git" / "refs" / "heads").mkdir(parents=True)
    (tmp_path / ".git" / "HEAD").write_text("ref: refs/heads/main\n")
    assert git_commit(tmp_path, built) == ""
    (tmp_path / ".git" / "packed-refs").write_text(f"# pack-refs\n{sha} refs/heads/main\n")
    assert git_commit(tmp_path) == sha
    (tmp_path / ".git" / "refs" / "heads" / "main").write_text(sha.replace("0", "f") + "\n")
    assert git_commit(tmp_path) == sha.replace("0", "f")
    (tmp_path / ".git" / "HEAD").write_text(sha)
    assert git_commit(tmp_path) == sha
    assert git_commit(tmp_path / "nowhere") == ""


def test_profile_name_comes_from_the_supervisor_state(tmp_path, monkeypatch):
    monkeypatch.setenv("STACK_HOME", str(tmp_path))
    write_state("v1", {"pid": 321, "profile": "/x/launch/sitl_quad.toml"})
    assert profile_name("v1", 321) == "sitl_quad"
    assert profile_name("v1", 999) == "" and profile_name("v2", 321) == ""


class FakeSubscriber:
    def __init__(self, samples) -> None:
        self.samples = list(samples)

    def try_recv(self):
        return self.samples.pop(0) if self.samples else None


def gyro_samples(n: int) -> list[FakeSample]:
    return [
        FakeSample("stack/v1/sensor_gyro/0", msgspec.msgpack.encode(SensorGyro(timestamp=k)), header(GYRO_FP, 5, k, k))
        for k in range(1, n + 1)
    ]


def test_the_pump_drains_the_queue_then_finishes_the_file(tmp_path):
    path = tmp_path / "p.mcap"
    sink = SampleRecorder(RecordingWriter(path, RecordingInfo()), TopicSelection(), True)
    pump = RecordingPump(FakeSubscriber(gyro_samples(500)), sink, logging.getLogger("test"))
    pump.start()
    assert pump.stop() and pump.failed is None
    with RecordingReader(path) as reader:
        assert reader.complete and [m.index for m in reader.iter_messages()] == list(range(1, 501))


def test_a_failing_disk_stops_the_recording_but_never_the_bus(tmp_path):
    class DiskFull(SampleRecorder):
        def handle(self, sample) -> None:
            if self.writer.messages == 10:
                raise OSError(28, "No space left on device")
            super().handle(sample)

    path = tmp_path / "p.mcap"
    queue = FakeSubscriber(gyro_samples(100))
    pump = RecordingPump(
        queue, DiskFull(RecordingWriter(path, RecordingInfo()), TopicSelection(), True), logging.getLogger("t")
    )
    pump.start()
    deadline = time.monotonic() + 5.0
    while queue.samples and time.monotonic() < deadline:
        time.sleep(0.01)
    assert queue.samples == []  # still drained
    assert pump.stop()
    assert pump.failed == f"cannot write {path}: No space left on device" and pump.discarded == 89
    with RecordingReader(path) as reader:
        assert reader.complete and len(list(reader.iter_messages())) == 10


def test_publishers_are_named_by_module_and_a_garbled_table_names_none():
    info = RecordingInfo(vehicle="v1", publishers={0x1234ABCD: "commander", 7: "simulator"})
    back = RecordingInfo.from_metadata(info.to_metadata())
    assert back.publishers == info.publishers and "publishers" not in back.extra
    assert back.publisher_name(0x1234ABCD) == "commander" and back.publisher_name(0xFF) == "000000ff"
    for garbled in ("not json", "[1, 2]", '{"zz": "x", "0a": "ok"}'):
        assert RecordingInfo.from_metadata({**info.to_metadata(), "publishers": garbled}).publishers in ({}, {10: "ok"})
