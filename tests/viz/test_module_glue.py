"""The rerun_bridge module on a bench, plotting to an .rrd file (no viewer, no web server): what it reads, in which
order it hands the logger what arrived, when it flushes, how it reports full buffers, the rotor geometry it asks
for, how it refuses bad arguments and stays idle without an output, and what close() leaves in the file."""

import logging
import re

import pytest

from stack.msg.estimation import VehicleAngularVelocity
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint, VehicleTorqueSetpoint
from stack.viz import layout as lay
from stack.viz import module as viz_module
from stack.viz.logger import TOPICS, FlightLogger
from stack.viz.module import FLUSH_EVERY_TICKS, RerunBridgeModule, wall_time_us
from tests.support.bench import ModuleBench, stand_in
from tests.viz.rrd import read_rrd

TICK = 0.04  # the module's 25 Hz timer


def bridge(tmp_path, **args) -> ModuleBench:
    """A bridge saving every message to tmp_path/plots.rrd, its timeline starting at 0 (as in lockstep)."""
    args = {"spawn": False, "save": str(tmp_path / "plots.rrd"), "plot_rate_hz": 0.0, **args}
    return ModuleBench(RerunBridgeModule, args=args, vehicle="v3", run_dir=str(tmp_path / "run-42"), lockstep=True)


def test_reads_each_drawn_topic_through_a_drop_oldest_ring_of_its_queue_and_publishes_nothing(tmp_path):
    bench = bridge(tmp_path, queue=64)
    try:
        assert set(bench.inputs) == {(t.name, 0) for t in TOPICS}
        assert set(bench.node.subscriptions) == set(bench.inputs)
        assert {(s.keep_last, s.capacity) for s in bench.node.subscriptions.values()} == {(True, 64)}
        assert bench.outputs == {}
        assert bench.module.sinks.rec.get_recording_id() == "v3-run-42"
    finally:
        bench.module.close()


def test_what_arrived_goes_to_the_logger_oldest_first_across_topics_stamped_with_the_tick(tmp_path, monkeypatch):
    logged = stand_in(monkeypatch, FlightLogger, "log_message", through=True)
    bench = bridge(tmp_path)
    before = wall_time_us()
    bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=3_000))
    bench.put(ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity(timestamp=1_000))
    bench.put(ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity(timestamp=4_000))
    bench.put(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(timestamp=2_000))
    bench.run(None, TICK)
    after = wall_time_us()
    assert [(topic, instance, msg.timestamp) for topic, instance, msg, _ in logged] == [
        ("vehicle_angular_velocity", 0, 1_000),
        ("vehicle_thrust_setpoint", 0, 2_000),
        ("vehicle_torque_setpoint", 0, 3_000),
        ("vehicle_angular_velocity", 0, 4_000),
    ]
    assert len({wall for *_, wall in logged}) == 1 and before <= logged[0][3] <= after
    bench.run(None, TICK)
    assert len(logged) == 4  # nothing new, nothing logged again
    bench.module.close()


def test_it_flushes_every_fifth_tick(tmp_path, monkeypatch):
    flushes = stand_in(monkeypatch, FlightLogger, "flush", through=True)
    bench = bridge(tmp_path)
    bench.module._asking.join()
    at_start = len(flushes)
    counts = []
    for _ in range(2 * FLUSH_EVERY_TICKS):
        bench.run(None, TICK)
        counts.append(len(flushes) - at_start)
    assert counts == [0, 0, 0, 0, 1, 1, 1, 1, 1, 2]
    bench.module.close()


def test_a_buffer_found_full_is_an_overrun_reported_once_per_hundred(tmp_path, caplog):
    bench = bridge(tmp_path, queue=16)
    with caplog.at_level(logging.WARNING, logger="rerun_bridge"):
        for k in range(20):  # the ring keeps the 16 newest
            bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=1_000 * (k + 1)))
        bench.run(None, TICK)
        for k in range(16):
            bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=100_000 + 1_000 * k))
        bench.run(None, TICK)
        bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=200_000))
        bench.run(None, TICK)
    assert bench.module.overruns == 2
    full = [m for m in caplog.messages if "ring buffer of 16 full" in m]
    assert full == ["vehicle_torque_setpoint: ring buffer of 16 full, oldest samples dropped (1 overruns so far)"]
    assert bench.module.logger.messages == 16 + 16 + 1
    status = bench.module.status()
    assert (status["messages"], status["overruns"], status["lost"]) == (33, 2, 0)
    assert status["plotted"] == bench.module.logger.kept > 0
    bench.module.close()


def test_the_vehicle_is_drawn_with_the_rotors_of_whichever_module_serves_them(tmp_path, monkeypatch):
    hexa = tuple((0.1 * i, -0.1 * i, 0.0) for i in range(6))
    asked = []
    monkeypatch.setattr(viz_module, "query_rotors", lambda session, vehicle: asked.append((session, vehicle)) or hexa)
    bench = bridge(tmp_path)
    bench.module._asking.join()
    assert asked == [(bench.node.session, "v3")]
    assert len(bench.module.logger.rotors) == 4  # the generic quad until a run takes the answer
    bench.run(None, TICK)
    assert bench.module.logger.rotors == hexa
    bench.module.close()


def test_without_an_answer_the_generic_quad_stays(tmp_path):
    bench = bridge(tmp_path)
    bench.module._asking.join()
    drawn = bench.module.logger.rotors
    bench.run(None, TICK)
    assert bench.module.logger.rotors == drawn and len(drawn) == 4
    assert bench.node.session.queries == ["stack/v3/@param/*"]
    bench.module.close()


def test_without_a_display_and_nothing_to_save_it_stays_idle(tmp_path, monkeypatch, caplog):
    monkeypatch.setattr(viz_module, "has_display", lambda: False)
    with caplog.at_level(logging.WARNING, logger="rerun_bridge"):
        bench = ModuleBench(RerunBridgeModule)  # spawn is the default
    assert caplog.messages == [
        "no display: not opening a viewer (use web or save)",
        "nothing to plot to: no viewer, no web viewer, no file; the bridge stays idle",
    ]
    assert bench.inputs == {} and bench.node.session.queries == [] and bench.module.logger is None
    bench.run(None, TICK)
    bench.module.close()


@pytest.mark.parametrize("args", [{"queue": 15}, {"plot_rate_hz": -1.0}, {"window_s": -0.5}])
def test_bad_arguments_are_refused(tmp_path, args):
    refusal = "rerun_bridge: queue must be >= 16, plot_rate_hz and window_s >= 0"
    with pytest.raises(ValueError, match=f"^{re.escape(refusal)}$"):
        bridge(tmp_path, **args)
    assert not (tmp_path / "plots.rrd").exists()


def test_close_plots_what_is_still_queued_and_finishes_the_file(tmp_path, caplog):
    bench = bridge(tmp_path)
    bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=4_000, xyz=(0.1, 0.2, 0.3)))
    bench.run(None, TICK)
    bench.put(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp=8_000, xyz=(0.4, 0.5, 0.6)))
    with caplog.at_level(logging.INFO, logger="rerun_bridge"):
        bench.module.close()  # the second message never saw a run
    assert any(m.startswith("plotted 2 of 2 messages in ") and m.endswith("; 0 buffer overruns, 0 samples lost")
               for m in caplog.messages)
    plots = read_rrd(tmp_path / "plots.rrd")
    assert plots.times(lay.TORQUE) == [4_000, 8_000]
    assert plots.values(lay.TORQUE) == [pytest.approx([0.1, 0.2, 0.3]), pytest.approx([0.4, 0.5, 0.6])]
    assert plots.blueprints
