"""The recorder module on a bench: what it asks of the bus, what it writes and with which clock, how it refuses a
path, and how it finishes the file (after PX4's logger, src/modules/logger/logger.cpp: every topic, a file per
run). Its pieces (SampleRecorder, RecordingPump) are tested in test_recorder_parts.py."""

import logging

import msgspec
import pytest
import zenoh

from stack.bus.node import stable_publisher_id, wall_clock_us
from stack.bus.topics import FLAG_LOCKSTEP_TIME, HEADER
from stack.msg.registry import fingerprint
from stack.msg.sensors import SensorGyro
from stack.msg.system import VehicleStatus
from stack.record import module as recorder_module
from stack.record.module import RecorderModule, RecordingPump
from stack.record.recorder import RecordingReader
from tests.support.bench import ModuleBench


class Sample:
    """What the recorder reads of a zenoh.Sample."""

    def __init__(self, key: str, msg: object, publisher: int, index: int, t_us: int, flags: int = 0) -> None:
        self.key_expr = key
        self.payload = zenoh.ZBytes(msgspec.msgpack.encode(msg))
        header = HEADER.pack(fingerprint(type(msg)), publisher, index, index, t_us, flags, 0)
        self.attachment = zenoh.ZBytes(header)


def recorder(tmp_path, **args) -> tuple[ModuleBench, object]:
    bench = ModuleBench(RecorderModule, args={"path": str(tmp_path / "run" / "r.mcap"), **args},
                        vehicle="v7", peers={"commander": [], "simulator": []})
    return bench, bench.node.session.channels["stack/v7/*/*"]


def read(tmp_path) -> tuple[RecordingReader, list]:
    reader = RecordingReader(tmp_path / "run" / "r.mcap")
    return reader, list(reader.iter_messages())


def test_it_reads_every_topic_of_its_vehicle_through_one_raw_subscriber_and_publishes_nothing(tmp_path):
    bench, channel = recorder(tmp_path)
    try:
        assert bench.inputs == {} and bench.outputs == {}
        assert list(bench.node.session.channels) == ["stack/v7/*/*"]
        assert isinstance(channel.handler, zenoh.handlers.FifoChannel)
        assert RecorderModule.PASSIVE and RecorderModule.LOSSLESS
    finally:
        bench.module.close()
    assert channel.undeclared


def test_what_arrives_is_in_the_file_once_closed_logged_at_the_wall_clock_in_real_time(tmp_path):
    start = wall_clock_us()
    bench, channel = recorder(tmp_path)
    gyro = SensorGyro(timestamp=5_000, x=0.25)
    channel.samples.extend([
        Sample("stack/v7/sensor_gyro/0", gyro, publisher=11, index=1, t_us=5_000),
        Sample("stack/v7/vehicle_status/0", VehicleStatus(timestamp=6_000, arming_state=2), 12, 1, 6_000),
    ])
    bench.run(None, 0.05)
    bench.module.close()
    end = wall_clock_us()
    reader, messages = read(tmp_path)
    with reader:
        assert reader.complete
        assert reader.info.vehicle == "v7" and not reader.info.lockstep
        assert reader.info.publishers == {
            stable_publisher_id("v7", "commander"): "commander",
            stable_publisher_id("v7", "simulator"): "simulator",
        }
    assert [(m.topic, m.instance, m.publisher_id, m.pub_time_us) for m in messages] == [
        ("sensor_gyro", 0, 11, 5_000),
        ("vehicle_status", 0, 12, 6_000),
    ]
    assert start <= messages[0].log_time_us <= messages[1].log_time_us <= end
    assert messages[0].msg == gyro and messages[1].msg.arming_state == 2
    assert bench.module.status() == {"recorded": 2, "undecoded": 0, "record_errors": 0, "fast_lost": 0}


def test_in_lockstep_a_message_is_logged_at_the_simulated_time_reached(tmp_path):
    bench = ModuleBench(RecorderModule, args={"path": str(tmp_path / "run" / "r.mcap")}, lockstep=True)
    channel = bench.node.session.channels["stack/v1/*/*"]
    channel.samples.extend([
        Sample("stack/v1/sensor_gyro/0", SensorGyro(), 11, 1, 8_000, FLAG_LOCKSTEP_TIME),
        Sample("stack/v1/sensor_gyro/0", SensorGyro(), 99, 1, 10**12),  # a tool's wall-clock publication
    ])
    bench.module.close()
    reader, messages = read(tmp_path)
    with reader:
        assert reader.info.lockstep
    assert [(m.publisher_id, m.log_time_us) for m in messages] == [(11, 8_000), (99, 8_000)]


def test_only_the_selected_topics_are_recorded(tmp_path):
    bench, channel = recorder(tmp_path, topics="sensor_gyro/1")
    channel.samples.extend(Sample(f"stack/v7/sensor_gyro/{i}", SensorGyro(), 11, 1, 10) for i in range(3))
    bench.module.close()
    reader, messages = read(tmp_path)
    reader.close()
    assert [(m.topic, m.instance) for m in messages] == [("sensor_gyro", 1)]


def test_the_running_count_is_logged_every_status_period(tmp_path, monkeypatch, caplog):
    monkeypatch.setattr(recorder_module, "STATUS_PERIOD_S", 0.0)
    bench, _ = recorder(tmp_path)
    with caplog.at_level(logging.INFO, logger="recorder"):
        bench.run(None, 0.05)
    bench.module.close()
    assert "recorded 0 messages (0 undecoded) to r.mcap" in caplog.messages


@pytest.mark.parametrize(
    ("args", "refusal"),
    [
        ({}, "recorder: the argument 'path' is required"),
        ({"path": "  "}, "recorder: the argument 'path' is required"),
        ({"path": "{tmp}/a_file/r.mcap"}, "recorder: cannot write {tmp}/a_file/r.mcap"),
    ],
)
def test_a_missing_or_unwritable_path_is_refused(tmp_path, args, refusal):
    (tmp_path / "a_file").write_text("not a directory")
    args = {k: v.format(tmp=tmp_path) for k, v in args.items()}
    with pytest.raises(ValueError, match="^" + refusal.format(tmp=tmp_path)):
        ModuleBench(RecorderModule, args=args)


def test_a_recording_not_finished_in_time_is_reported_and_its_subscriber_kept(tmp_path, monkeypatch, caplog):
    stop = RecordingPump.stop
    monkeypatch.setattr(RecordingPump, "stop", lambda self: stop(self) and False)
    bench, channel = recorder(tmp_path)
    with caplog.at_level(logging.ERROR, logger="recorder"):
        bench.module.close()
    assert not channel.undeclared
    assert any("not finished in time: the file lacks its summary" in m for m in caplog.messages)
