"""RecordingWriter and RecordingReader: exact round trips, refusals, and reading what a cut file still holds."""

import io
import math
import os
import random
import struct

import msgspec
import pytest
from mcap.writer import Writer

from stack.msg.base import Message
from stack.msg.registry import fingerprint
from stack.msg.sensors import SensorGyro
from stack.msg.setpoints import VehicleRatesSetpoint
from stack.record.mcapscan import PREFIX
from stack.record.recorder import RecordingError, RecordingInfo, RecordingReader, RecordingWriter

INFO = RecordingInfo(vehicle="v9", profile="sitl_quad", seed=42, lockstep=True, start_unix_ns=123, git_commit="ab" * 20)
NEG_NAN = math.copysign(math.nan, -1.0)
enc = msgspec.msgpack.encode


def flight(n: int, seed: int = 3) -> list[tuple]:
    """(topic, instance, msg, publisher, index, pub_time, flags, log_time) of a made-up lockstep flight."""
    rng = random.Random(seed)
    out = []
    for k in range(1, n + 1):
        t = 4000 * k
        x = rng.uniform(-1, 1)
        gyro = SensorGyro(timestamp=t, timestamp_sample=t - 100, x=x, y=math.inf if k % 7 == 0 else x, z=NEG_NAN)
        out.append(("sensor_gyro", k % 2, gyro, 0xAAAA0001, (k + 1) // 2 if k % 2 else k // 2, t, 1, t))
        if k % 5 == 0:
            sp = VehicleRatesSetpoint(timestamp=t, roll=x, thrust_body=(0.0, 0.0, -0.5))
            out.append(("vehicle_rates_setpoint", 0, sp, 0xBBBB0002, k // 5, t, 1, t + 1))
    return out


def write(path, records, **kwargs) -> None:
    with RecordingWriter(path, INFO, **kwargs) as w:
        for r in records:
            w.write(*r)


def key(m) -> tuple:
    return (m.topic, m.instance, m.publisher_id, m.index, m.pub_time_us, m.flags, m.log_time_us, m.wire_payload())


def expected_key(r) -> tuple:
    topic, instance, msg, pub, index, t, flags, log = r
    return (topic, instance, pub, index, t, flags, log, enc(msg))


def test_round_trip_is_exact_with_every_header_field(tmp_path):
    path = tmp_path / "flight.mcap"
    records = flight(2000)
    big_index = (5 << 32) + 7  # beyond MCAP's 32-bit sequence: kept through the channel's index epoch
    records.append(("sensor_gyro", 0, SensorGyro(timestamp=1), 0xAAAA0001, big_index, 0, 0, 9_000_000))
    write(path, records)
    with RecordingReader(path) as reader:
        assert reader.complete and reader.warnings == []
        assert reader.info == INFO
        got = list(reader.iter_messages())
        assert [key(m) for m in got] == [expected_key(r) for r in records]
        assert all(type(m.msg) is type(r[2]) for m, r in zip(got, records, strict=True))
        assert got[0].lockstep_time and not got[-1].lockstep_time
        summary = reader.summary()
        assert summary.message_count == len(records)
        assert (summary.start_us, summary.end_us) == (4000, 9_000_000)
        counts = {(c.topic, c.instance): c.message_count for c in reader.channels() if c.index_epoch == 0}
        assert counts == {("sensor_gyro", 0): 1000, ("sensor_gyro", 1): 1000, ("vehicle_rates_setpoint", 0): 400}
        gyro = next(c for c in reader.channels() if c.topic == "sensor_gyro")
        assert gyro.type_name == "SensorGyro" and gyro.fingerprint == fingerprint(SensorGyro) and gyro.decodable
        assert gyro.publisher_id == 0xAAAA0001 and gyro.flags == 1 and gyro.encoding == "json"


def test_topic_selection(tmp_path):
    path = tmp_path / "flight.mcap"
    records = flight(100)
    write(path, records)
    with RecordingReader(path) as reader:
        assert {(m.topic, m.instance) for m in reader.iter_messages(["sensor_gyro/1"])} == {("sensor_gyro", 1)}
        assert len(list(reader.iter_messages(["sensor_gyro"]))) == 100
        assert len(list(reader.iter_messages(["vehicle_rates_setpoint,sensor_gyro/0"]))) == 70


def test_undecodable_payloads_and_foreign_schemas_are_kept(tmp_path):
    class CustomStatus(Message):
        level: float = 0.0
        label: str = ""

    path = tmp_path / "odd.mcap"
    custom = CustomStatus(timestamp=7, level=math.inf, label="x")
    with RecordingWriter(path, INFO) as w:
        w.write_raw("sensor_gyro", 0, b"\xc1garbage", 0x1234, 5, 1, 100, 1, 100, "payload does not decode")
        w.write("custom_status", 0, custom, 6, 1, 200, 0, 200)
    with RecordingReader(path) as reader:
        raw, foreign = reader.iter_messages()
        assert raw.msg is None and raw.payload == b"\xc1garbage" and raw.wire_payload() == b"\xc1garbage"
        assert raw.fingerprint == 0x1234
        assert foreign.msg is None and foreign.fields == {"timestamp": 7, "level": math.inf, "label": "x"}
        assert foreign.wire_payload() == enc(custom)  # republished exactly as the bus carried it
        channels = {c.topic: c for c in reader.channels()}
        assert channels["sensor_gyro"].raw_reason == "payload does not decode"
        assert channels["sensor_gyro"].encoding == "msgpack" and not channels["sensor_gyro"].decodable
        assert not channels["custom_status"].decodable and channels["custom_status"].type_name == "CustomStatus"


def test_files_that_are_not_recordings_are_refused_in_one_line(tmp_path):
    def refused(name: str, data: bytes) -> str:
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(RecordingError) as e:
            RecordingReader(path)
        text = str(e.value)
        assert text.startswith(f"{path}: ") and "\n" not in text
        return text

    rng = random.Random(1)
    assert "not an MCAP file" in refused("random.mcap", bytes(rng.getrandbits(8) for _ in range(4096)))
    assert "empty file" in refused("empty.mcap", b"")
    good = tmp_path / "good.mcap"
    write(good, flight(10))
    data = good.read_bytes()
    assert "not an MCAP file" in refused("magic.mcap", b"\x89MCAP1\r\n" + data[8:])
    assert "first record" in refused("header.mcap", data[:8] + bytes([0x05]) + data[9:])
    assert "truncated" in refused("stub.mcap", data[:40])

    other = io.BytesIO()
    w = Writer(other)
    w.start()
    w.add_metadata("ros", {"distro": "jazzy"})
    w.finish()
    assert "not a stack recording" in refused("ros.mcap", other.getvalue())
    with pytest.raises(RecordingError, match="cannot open"):
        RecordingReader(tmp_path / "missing.mcap")


def chunk_offsets(data: bytes) -> list[tuple[int, int]]:
    pos, out = 8, []
    while pos < len(data):
        opcode, length = PREFIX.unpack_from(data, pos)
        if opcode == 0x06:
            out.append((pos, length))
        if opcode == 0x0F:
            return out
        pos += PREFIX.size + length
    return out


def test_a_cut_file_yields_every_complete_message_before_the_cut(tmp_path):
    path = tmp_path / "flight.mcap"
    records = flight(20000)
    write(path, records, chunk_size=64 * 1024)
    data = path.read_bytes()
    expected = [expected_key(r) for r in records]
    chunks = chunk_offsets(data)
    assert len(chunks) > 10
    recovered = []
    for fraction in (0.2, 0.5, 0.8):
        cut = int(len(data) * fraction)
        short = tmp_path / f"cut-{fraction}.mcap"
        short.write_bytes(data[:cut])
        with RecordingReader(short) as reader:
            assert not reader.complete
            got = [key(m) for m in reader.iter_messages()]
            assert got == expected[: len(got)]
            complete_chunks = sum(1 for offset, length in chunks if offset + PREFIX.size + length <= cut)
            assert len(got) >= complete_chunks * 100
            assert any(
                "truncated or damaged" in w and f"the {len(got)} complete messages" in w for w in reader.warnings
            )
            assert any("incomplete recording" in w for w in reader.warnings)
            assert reader.summary().message_count == len(got)
            recovered.append(len(got))
    assert 0 < recovered[0] < recovered[1] < recovered[2] < len(records)

    # Cut inside the summary: every message is there, only the summary is missing.
    short = tmp_path / "cut-summary.mcap"
    short.write_bytes(data[:-20])
    with RecordingReader(short) as reader:
        assert [key(m) for m in reader.iter_messages()] == expected
        assert len(reader.warnings) == 1 and "incomplete recording" in reader.warnings[0]


def test_the_readable_start_of_a_cut_chunk_is_recovered(tmp_path):
    path = tmp_path / "one-chunk.mcap"
    records = flight(20000)
    write(path, records, chunk_size=1 << 30)  # a single chunk of several zstd blocks
    data = path.read_bytes()
    ((offset, length),) = chunk_offsets(data)
    short = tmp_path / "cut.mcap"
    short.write_bytes(data[: offset + PREFIX.size + int(length * 0.7)])
    with RecordingReader(short) as reader:
        got = [key(m) for m in reader.iter_messages()]
    assert 0 < len(got) < len(records)
    assert got == [expected_key(r) for r in records[: len(got)]]


def test_a_flushed_file_is_readable_while_still_being_written(tmp_path):
    """What a crash leaves: everything up to the last flush (at least once a second)."""
    path = tmp_path / "live.mcap"
    records = flight(3000)
    w = RecordingWriter(path, INFO, flush_interval_s=0.0)
    try:
        for r in records:
            w.write(*r)
        w.flush_if_due()
        with RecordingReader(path) as reader:
            assert not reader.complete
            assert [key(m) for m in reader.iter_messages()] == [expected_key(r) for r in records]
            assert any("the file ends at byte" in w for w in reader.warnings)
    finally:
        w.close()


def test_a_corrupt_chunk_is_skipped_and_the_rest_is_read(tmp_path):
    path = tmp_path / "flight.mcap"
    records = flight(5000)
    write(path, records, chunk_size=32 * 1024)
    data = bytearray(path.read_bytes())
    chunks = chunk_offsets(bytes(data))
    offset, length = chunks[2]
    middle = offset + PREFIX.size + length // 2
    data[middle : middle + 16] = bytes(16)
    path.write_bytes(bytes(data))
    with RecordingReader(path) as reader:
        got = [key(m) for m in reader.iter_messages()]
        assert any(f"chunk at byte {offset}" in w for w in reader.warnings)
    expected = [expected_key(r) for r in records]
    assert len(expected) > len(got) > len(expected) - 1000
    assert got[0] == expected[0] and got[-1] == expected[-1]
    assert set(got) <= set(expected)


def test_writer_refuses_an_unknown_compression(tmp_path):
    with pytest.raises(ValueError, match="compression"):
        RecordingWriter(tmp_path / "x.mcap", INFO, compression="gzip")
    assert not os.path.exists(tmp_path / "x.mcap")


def test_metadata_survives_round_trip_of_unknown_keys(tmp_path):
    info = RecordingInfo(vehicle="v1", seed=None, extra={"mission": "survey"})
    path = tmp_path / "x.mcap"
    with RecordingWriter(path, info):
        pass
    with RecordingReader(path) as reader:
        assert reader.info.extra == {"mission": "survey"} and reader.info.seed is None
        assert reader.summary().message_count == 0 and list(reader.iter_messages()) == []


def test_chunk_header_layout_matches_the_spec():
    """The scanner parses chunk headers itself; check its layout against mcap's writer."""
    from mcap.data_stream import RecordBuilder
    from mcap.records import Chunk

    builder = RecordBuilder()
    Chunk(
        compression="zstd",
        data=b"abc",
        message_start_time=1,
        message_end_time=2,
        uncompressed_crc=3,
        uncompressed_size=4,
    ).write(builder)
    raw = builder.end()
    assert struct.unpack_from("<QQQI", raw, 9) == (1, 2, 4, 3)
    assert raw[9 + 28 : 9 + 32] == struct.pack("<I", 4) and raw[9 + 32 : 9 + 36] == b"zstd"


def test_mcap_own_reader_opens_it_and_every_message_is_json_of_its_schema(tmp_path):
    """What Foxglove and PlotJuggler rely on: the summary, one schema per channel, JSON objects."""
    import json

    from mcap.reader import make_reader

    path = tmp_path / "flight.mcap"
    write(path, flight(500))
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics.message_count == 600
        for schema in summary.schemas.values():
            assert schema.encoding == "jsonschema"
        for channel in summary.channels.values():
            assert channel.message_encoding == "json" and channel.schema_id in summary.schemas
            assert channel.topic.startswith("/")
        seen = 0
        for schema, _channel, message in reader.iter_messages():
            properties = json.loads(schema.data)["properties"]
            obj = json.loads(message.data, parse_constant=lambda c: pytest.fail(f"non-JSON {c}"))
            assert list(obj) == list(properties)
            assert message.publish_time % 1000 == 0 and message.log_time >= message.publish_time
            seen += 1
        assert seen == 600
