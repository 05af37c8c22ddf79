"""export_rrd: a recording replayed into an .rrd file with the live layout."""

from dataclasses import dataclass
from typing import Any

from stack.mathlib.quaternion import from_euler
from stack.msg.estimation import VehicleAttitude
from stack.msg.sensors import SensorBaro, SensorGyro
from stack.msg.system import VehicleStatus
from stack.record.recorder import RecordingReader, RecordingWriter, new_recording_info
from stack.viz import layout as lay
from stack.viz.export import export_rrd
from tests.viz.rrd import read_rrd


@dataclass(frozen=True)
class FakeMessage:
    topic: str
    instance: int
    log_time_us: int
    lockstep_time: bool
    msg: Any


@dataclass(frozen=True)
class FakeInfo:
    vehicle: str = "v7"
    lockstep: bool = False
    start_unix_ns: int = 0


class FakeReader:
    def __init__(self, messages: list[FakeMessage], info: FakeInfo | None = None) -> None:
        self.messages = messages
        if info is not None:
            self.info = info

    def iter_messages(self, topics=None):
        wanted = set(topics) if topics is not None else None
        return (m for m in self.messages if wanted is None or m.topic in wanted)


def lockstep_flight(steps: int) -> list[FakeMessage]:
    q = from_euler(0.1, 0.0, 0.0)
    msgs = []
    for k in range(1, steps + 1):
        t = 4000 * k
        msgs.append(FakeMessage("vehicle_attitude", 0, t, True, VehicleAttitude(timestamp=t, q=q)))
        msgs.append(FakeMessage("sensor_gyro", 0, t, True, SensorGyro(timestamp=t)))
    msgs.append(FakeMessage("vehicle_status", 0, 8000, True, VehicleStatus(timestamp=8000)))
    msgs.append(FakeMessage("vehicle_attitude", 0, 8000, True, None))  # a schema this build cannot decode
    return msgs


def test_lockstep_recording_exports_every_message_on_sim_time_only(tmp_path):
    calls = []
    out = tmp_path / "out" / "flight.rrd"
    summary = export_rrd(
        FakeReader(lockstep_flight(250)), out, progress=lambda done, total: calls.append((done, total))
    )
    assert (summary.messages, summary.drawn) == (252, 251)
    assert summary.duration_s == 0.996
    assert calls[-1] == (252, 0)
    rrd = read_rrd(out)
    assert rrd.rows(lay.attitude_path("roll", lay.ESTIMATE)) == 250
    assert rrd.times(lay.attitude_path("roll", lay.ESTIMATE))[:2] == [4000, 8000]
    assert rrd.timelines[lay.attitude_path("roll", lay.ESTIMATE)] == {lay.SIM_TIME}
    assert [v[0] for v in rrd.values(lay.EVENTS, "TextLog:text")] == ["mode MANUAL, disarmed"]
    assert rrd.blueprints and rrd.recordings[0].application_id == lay.APPLICATION_ID
    assert rrd.recordings[0].recording_id == "vehicle-flight"


def test_real_time_recording_maps_log_times_to_wall_time(tmp_path):
    start_unix_ns = 1_750_000_000_000_000_000
    monotonic0 = 123_456_000_000
    msgs = [
        FakeMessage("sensor_baro", 0, monotonic0 + 50_000 * k, False, SensorBaro(timestamp=monotonic0 + 50_000 * k))
        for k in range(10)
    ]
    out = tmp_path / "rt.rrd"
    summary = export_rrd(FakeReader(msgs, FakeInfo(start_unix_ns=start_unix_ns)), out)
    assert summary.drawn == 10
    rrd = read_rrd(out)
    assert rrd.times(lay.BARO_PRESSURE) == [50_000 * k for k in range(10)]
    assert rrd.timelines[lay.BARO_PRESSURE] == {lay.SIM_TIME, lay.WALL_TIME}
    assert rrd.recordings[0].recording_id == "v7-rt"


def test_decimated_export(tmp_path):
    out = tmp_path / "decimated.rrd"
    export_rrd(FakeReader(lockstep_flight(250)), out, plot_rate_hz=50.0)
    assert read_rrd(out).rows(lay.attitude_path("roll", lay.ESTIMATE)) == 51


def test_round_trip_through_a_stack_recording(tmp_path):
    mcap = tmp_path / "flight.mcap"
    with RecordingWriter(mcap, new_recording_info("v1", "test", 3, True, "")) as writer:
        for k in range(1, 101):
            t = 4000 * k
            writer.write("vehicle_attitude", 0, VehicleAttitude(timestamp=t), 0x1234, k, t, 1, t)
            writer.write("sensor_baro", 0, SensorBaro(timestamp=t, pressure=101325.0), 0x1234, 1000 + k, t, 1, t)
            writer.write("sensor_gyro", 0, SensorGyro(timestamp=t), 0x1234, 2000 + k, t, 1, t)  # not drawn
    out = tmp_path / "flight.rrd"
    with RecordingReader(mcap) as reader:
        calls = []
        summary = export_rrd(reader, out, progress=lambda done, total: calls.append((done, total)))
    assert summary.messages == 200
    assert calls[-1] == (200, 200)
    rrd = read_rrd(out)
    assert rrd.rows(lay.attitude_path("yaw", lay.ESTIMATE)) == 100
    assert rrd.values(lay.BARO_PRESSURE)[0] == [101325.0]
    assert rrd.timelines[lay.BARO_PRESSURE] == {lay.SIM_TIME}
