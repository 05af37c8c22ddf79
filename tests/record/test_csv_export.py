"""CSV export: one file per topic instance, fields spread into columns, exact values."""

import csv
import math

from stack.msg.base import Message
from stack.msg.sensors import SensorGyro
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import VehicleCommandAck
from stack.record.csvexport import export_csv
from stack.record.recorder import RecordingInfo, RecordingReader, RecordingWriter


def rows(path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def test_one_csv_per_topic_instance_with_spread_arrays(tmp_path):
    class Odd(Message):
        flags: tuple[bool, bool] = (False, False)

    mcap = tmp_path / "flight.mcap"
    with RecordingWriter(mcap, RecordingInfo(vehicle="v1", lockstep=True)) as w:
        for k in range(1, 6):
            t = 1000 * k
            gyro = SensorGyro(timestamp=t, x=0.1 * k, y=math.inf, z=-math.inf, clip_counter=(k, 0, 2))
            w.write("sensor_gyro", 0, gyro, 0xAB, k, t, 1, t)
            w.write("sensor_gyro", 1, SensorGyro(timestamp=t, x=-1.0), 0xCD, k, t, 1, t)
        w.write("sim_groundtruth", 0, SimGroundtruth(timestamp=1, on_ground=True, motors=(0.5,)), 0xEF, 1, 1, 1, 1)
        w.write(
            "sim_groundtruth", 0, SimGroundtruth(timestamp=2, on_ground=False, motors=(0.1, 0.2, 0.3)), 0xEF, 2, 2, 1, 2
        )
        w.write("vehicle_command_ack", 0, VehicleCommandAck(reason='says "no", twice'), 0x1, 1, 3, 0, 3)
        w.write("odd_topic", 0, Odd(flags=(True, False)), 0x2, 1, 4, 0, 4)
        w.write_raw("sensor_gyro", 2, b"\x90", 0x99, 0x3, 1, 5, 0, 5, "schema fingerprint differs")
    progress = []
    with RecordingReader(mcap) as reader:
        result = export_csv(reader, tmp_path / "csv", progress=progress.append)
    names = sorted(t.path.name for t in result.tables)
    assert names == [
        "odd_topic_0.csv",
        "sensor_gyro_0.csv",
        "sensor_gyro_1.csv",
        "sim_groundtruth_0.csv",
        "vehicle_command_ack_0.csv",
    ]
    assert sum(progress) == 15
    assert len(result.notes) == 1 and "sensor_gyro/2: 1 messages" in result.notes[0]
    assert "schema fingerprint differs" in result.notes[0]

    gyro = rows(tmp_path / "csv" / "sensor_gyro_0.csv")
    assert len(gyro) == 5
    first = gyro[0]
    assert list(first)[:6] == ["log_time_us", "pub_time_us", "publisher_id", "index", "timestamp", "timestamp_sample"]
    assert (first["log_time_us"], first["publisher_id"], first["index"]) == ("1000", "000000ab", "1")
    assert float(gyro[2]["x"]) == 0.1 * 3  # shortest exact float text
    assert (first["y"], first["z"], first["temperature"]) == ("inf", "-inf", "nan")
    assert [r["clip_counter[0]"] for r in gyro] == ["1", "2", "3", "4", "5"] and gyro[0]["clip_counter[2]"] == "2"

    truth = rows(tmp_path / "csv" / "sim_groundtruth_0.csv")
    assert [r["on_ground"] for r in truth] == ["1", "0"]
    assert [(r["motors[0]"], r["motors[1]"], r["motors[2]"]) for r in truth] == [("0.5", "", ""), ("0.1", "0.2", "0.3")]
    assert "motors[3]" not in truth[0]

    assert rows(tmp_path / "csv" / "vehicle_command_ack_0.csv")[0]["reason"] == 'says "no", twice'
    odd = rows(tmp_path / "csv" / "odd_topic_0.csv")[0]  # a type this build lacks, from its recorded schema
    assert (odd["flags[0]"], odd["flags[1]"]) == ("1", "0")


def test_selected_topics_only(tmp_path):
    mcap = tmp_path / "flight.mcap"
    with RecordingWriter(mcap, RecordingInfo()) as w:
        for k in range(1, 4):
            w.write("sensor_gyro", 0, SensorGyro(timestamp=k), 1, k, k, 0, k)
            w.write("sensor_gyro", 1, SensorGyro(timestamp=k), 2, k, k, 0, k)
    with RecordingReader(mcap) as reader:
        result = export_csv(reader, tmp_path / "out", topics=["sensor_gyro/1"])
    assert [(t.path.name, t.rows) for t in result.tables] == [("sensor_gyro_1.csv", 3)]
