"""FlightLogger: entities, units, decimation, events, derived errors, 3D scene — read back from .rrd files."""

import math

import pytest

from stack.mathlib.quaternion import from_euler
from stack.msg.actuators import ActuatorMotors, ActuatorOutputs, ControlAllocatorStatus
from stack.msg.estimation import VehicleAngularVelocity, VehicleAttitude, VehicleLocalPosition
from stack.msg.navigation import Mission, MissionItemEntry
from stack.msg.sensors import SensorBaro, SensorGps
from stack.msg.setpoints import (
    TrajectorySetpoint,
    VehicleAttitudeSetpoint,
    VehicleLocalPositionSetpoint,
    VehicleRatesSetpoint,
    VehicleThrustSetpoint,
    VehicleTorqueSetpoint,
)
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import HomePosition, VehicleCommandAck, VehicleStatus
from stack.viz import layout as lay
from stack.viz.logger import TOPICS, FlightLogger, new_recording
from tests.viz.rrd import read_rrd

NAN = math.nan
DEG = math.pi / 180.0


def open_logger(tmp_path, name="flight", **kwargs):
    path = tmp_path / f"{name}.rrd"
    rec = new_recording(name)
    rec.save(path, default_blueprint=lay.default_blueprint())
    return FlightLogger(rec, **kwargs), path


def close(logger):
    logger.flush()
    logger.rec.flush()
    logger.rec.disconnect()


def test_full_rate_keeps_every_message_with_its_time_and_value_in_degrees(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0)
    q = from_euler(30 * DEG, -10 * DEG, 90 * DEG)
    for k in range(1, 101):
        assert logger.log_message("vehicle_attitude", 0, VehicleAttitude(timestamp=4000 * k, q=q))
    close(logger)
    rrd = read_rrd(path)
    assert rrd.times(lay.attitude_path("roll", lay.ESTIMATE)) == [4000 * k for k in range(1, 101)]
    for axis, expected in (("roll", 30.0), ("pitch", -10.0), ("yaw", 90.0)):
        values = rrd.values(lay.attitude_path(axis, lay.ESTIMATE))
        assert len(values) == 100
        assert values[0] == [pytest.approx(expected, abs=1e-9)]
    assert rrd.recordings[0].application_id == lay.APPLICATION_ID
    assert rrd.blueprints, "the default blueprint is saved with the recording"
    # Typed like rr.Scalars, so the viewer's time series visualizer picks them up.
    kinds = rrd.kinds[lay.attitude_path("roll", lay.ESTIMATE)]
    assert kinds["Scalars:scalars"] == ("rerun.archetypes.Scalars", "rerun.components.Scalar")


def test_decimation_keeps_one_message_per_period_bucket(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=50.0)
    gyro_times = [4000 * k for k in range(1, 251)]  # 250 Hz for 1 s
    lpos_times = [12000 * k for k in range(1, 84)]  # 83.3 Hz
    for t in gyro_times:
        logger.log_message("vehicle_angular_velocity", 0, VehicleAngularVelocity(timestamp=t, xyz=(1.0, 0.0, 0.0)))
    for t in lpos_times:
        logger.log_message("vehicle_local_position", 0, VehicleLocalPosition(timestamp=t, x=1.0))
    for t in range(100_000, 1_000_001, 100_000):  # 10 Hz GPS: slower than the plot rate, all kept
        logger.log_message("sensor_gps", 0, SensorGps(timestamp=t, latitude_deg=47.0))
    close(logger)
    rrd = read_rrd(path)
    rates = rrd.times(lay.rates_path("roll", lay.ESTIMATE))
    assert len(rates) == len({t // 20000 for t in gyro_times}) == 51
    assert rates[:4] == [4000, 20000, 40000, 60000]
    assert rrd.values(lay.rates_path("roll", lay.ESTIMATE))[1] == [pytest.approx(180.0 / math.pi)]
    assert rrd.rows(lay.position_path("north", lay.ESTIMATE)) == len({t // 20000 for t in lpos_times})
    assert rrd.rows(lay.GPS_LATITUDE) == 10
    assert logger.messages == 250 + 83 + 10
    assert logger.kept == 51 + len({t // 20000 for t in lpos_times}) + 10


def test_every_drawn_topic_fills_its_entities(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0)
    t = 1000
    msgs = {
        "sim_groundtruth": SimGroundtruth(timestamp=t, position=(1.0, 2.0, -3.0), q=from_euler(0.0, 0.0, 0.5)),
        "vehicle_attitude": VehicleAttitude(timestamp=t),
        "vehicle_attitude_setpoint": VehicleAttitudeSetpoint(timestamp=t, q_d=from_euler(0.1, 0.0, 0.0)),
        "vehicle_angular_velocity": VehicleAngularVelocity(timestamp=t),
        "vehicle_rates_setpoint": VehicleRatesSetpoint(timestamp=t, roll=NAN),
        "vehicle_torque_setpoint": VehicleTorqueSetpoint(timestamp=t, xyz=(0.1, -0.2, 0.3)),
        "vehicle_thrust_setpoint": VehicleThrustSetpoint(timestamp=t, xyz=(0.0, 0.0, -0.6)),
        "actuator_motors": ActuatorMotors(timestamp=t, control=(0.1, 0.2, 0.3, 0.4) + (NAN,) * 8),
        "actuator_outputs_sim": ActuatorOutputs(timestamp=t, noutputs=4, output=(0.5,) * 16),
        "control_allocator_status": ControlAllocatorStatus(
            timestamp=t, unallocated_torque=(0.0, 0.1, 0.0), actuator_saturation=(2, 0, -2, 1) + (0,) * 12
        ),
        "vehicle_local_position": VehicleLocalPosition(timestamp=t, x=1.5, y=2.0, z=-2.0, eph=0.5),
        "vehicle_local_position_setpoint": VehicleLocalPositionSetpoint(timestamp=t, x=0.0, y=0.0, z=-5.0),
        "trajectory_setpoint": TrajectorySetpoint(timestamp=t, position=(0.0, 0.0, -5.0)),
        "sensor_gps": SensorGps(timestamp=t, latitude_deg=47.4, longitude_deg=8.5, altitude_msl_m=488.0),
        "sensor_baro": SensorBaro(timestamp=t, pressure=95000.0),
        "vehicle_status": VehicleStatus(timestamp=t),
        "vehicle_command_ack": VehicleCommandAck(timestamp=t, command=400),
        "home_position": HomePosition(timestamp=t, x=1.0, valid_lpos=True),
        "mission": Mission(timestamp=t, items=[MissionItemEntry(north=5.0, east=0.0, down=-5.0)]),
    }
    assert set(msgs) == {t.name for t in TOPICS}
    for topic, msg in msgs.items():
        assert logger.log_message(topic, 0, msg)
    close(logger)
    rrd = read_rrd(path)
    for axis in lay.AXES:
        for source in (lay.ESTIMATE, lay.SETPOINT, lay.TRUTH):
            assert rrd.rows(lay.attitude_path(axis, source)) == 1
            assert rrd.rows(lay.rates_path(axis, source)) == 1
    for axis in lay.NED:
        for source in (lay.ESTIMATE, lay.SETPOINT, lay.TRAJECTORY, lay.TRUTH):
            assert rrd.rows(lay.position_path(axis, source)) == 1
            assert rrd.rows(lay.velocity_path(axis, source)) == 1
    assert math.isnan(rrd.values(lay.rates_path("roll", lay.SETPOINT))[0][0])  # NaN: not controlled
    assert rrd.values(lay.TORQUE) == [pytest.approx([0.1, -0.2, 0.3])]
    assert rrd.values(lay.MOTOR_COMMANDS) == [pytest.approx([0.1, 0.2, 0.3, 0.4])]
    assert rrd.values(lay.MOTOR_OUTPUTS) == [pytest.approx([0.5] * 4)]
    assert rrd.values(lay.MOTOR_SATURATION) == [[2.0, 0.0, -2.0, 1.0]]
    assert rrd.values(lay.UNALLOCATED_TORQUE) == [pytest.approx([0.0, 0.1, 0.0])]
    assert rrd.values(lay.POSITION_ERROR) == [pytest.approx([0.5, 0.0, 1.0])]
    assert rrd.values(lay.ATTITUDE_ERROR) == [[pytest.approx(0.5 / DEG)]]
    accuracy = rrd.values(lay.ACCURACY)[0]
    assert accuracy[0] == pytest.approx(0.5) and math.isnan(accuracy[1])  # epv = inf is drawn as a gap
    assert rrd.values(lay.BARO_PRESSURE) == [[95000.0]]
    assert rrd.values(lay.GPS_LONGITUDE) == [[8.5]]
    assert rrd.values(lay.SETPOINT_MARKER, "Points3D:positions") == [[[0.0, 0.0, -5.0]]]
    assert rrd.rows(lay.VEHICLE) == 1
    assert len(rrd.values(lay.EVENTS, "TextLog:text")) == 2


def test_errors_need_the_truth_and_use_the_latest_truth_sample(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0)
    logger.log_message("vehicle_local_position", 0, VehicleLocalPosition(timestamp=1000, x=1.0))
    logger.log_message("vehicle_attitude", 0, VehicleAttitude(timestamp=1000))
    logger.log_message("sim_groundtruth", 0, SimGroundtruth(timestamp=2000, position=(0.0, 0.0, 0.0)))
    logger.log_message("sim_groundtruth", 0, SimGroundtruth(timestamp=3000, position=(0.25, 0.0, 0.0)))
    logger.log_message("vehicle_local_position", 0, VehicleLocalPosition(timestamp=3000, x=1.0, vx=2.0))
    close(logger)
    rrd = read_rrd(path)
    assert rrd.times(lay.POSITION_ERROR) == [3000]
    assert rrd.values(lay.POSITION_ERROR) == [pytest.approx([0.75, 0.0, 0.0])]
    assert rrd.values(lay.VELOCITY_ERROR) == [pytest.approx([2.0, 0.0, 0.0])]
    assert rrd.rows(lay.ATTITUDE_ERROR) == 0


def test_status_changes_become_text_events_and_are_never_decimated(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=1.0)
    armed = VehicleStatus.ARMING_STATE_ARMED
    posctl = VehicleStatus.NAVIGATION_STATE_POSCTL
    sequence = [
        VehicleStatus(timestamp=1000),
        VehicleStatus(timestamp=2000),
        VehicleStatus(timestamp=3000, arming_state=armed),
        VehicleStatus(timestamp=4000, arming_state=armed, nav_state=posctl),
        VehicleStatus(timestamp=5000, arming_state=armed, nav_state=posctl, failsafe=True),
        VehicleStatus(timestamp=6000, arming_state=armed, nav_state=posctl),
    ]
    for msg in sequence:
        logger.log_message("vehicle_status", 0, msg)
    denied = VehicleCommandAck.VEHICLE_CMD_RESULT_DENIED
    logger.log_message(
        "vehicle_command_ack", 0, VehicleCommandAck(timestamp=7000, command=400, result=denied, reason="not ready")
    )
    close(logger)
    rrd = read_rrd(path)
    texts = [v[0] for v in rrd.values(lay.EVENTS, "TextLog:text")]
    assert texts == [
        "mode MANUAL, disarmed",
        "armed",
        "mode MANUAL -> POSCTL",
        "failsafe active (mode POSCTL)",
        "failsafe cleared (mode POSCTL)",
        "command COMPONENT_ARM_DISARM (400): DENIED, not ready",
    ]
    levels = [v[0] for v in rrd.values(lay.EVENTS, "TextLog:level")]
    assert levels == ["INFO", "WARN", "INFO", "ERROR", "INFO", "WARN"]
    assert rrd.times(lay.EVENTS) == [1000, 3000, 4000, 5000, 6000, 7000]


def test_time_origin_and_wall_time(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0, time_origin_us=None)
    start = 5_000_000_000
    wall0 = 1_750_000_000_000_000
    for k in range(3):
        logger.log_message("sensor_baro", 0, SensorBaro(timestamp=start + 50_000 * k), wall0 + 50_000 * k)
    close(logger)
    rrd = read_rrd(path)
    assert rrd.times(lay.BARO_PRESSURE) == [0, 50_000, 100_000]
    assert rrd.timelines[lay.BARO_PRESSURE] == {lay.SIM_TIME, lay.WALL_TIME}

    logger, path = open_logger(tmp_path, "no_wall", plot_rate_hz=0.0)
    logger.log_message("sensor_baro", 0, SensorBaro(timestamp=7000))
    close(logger)
    rrd = read_rrd(path)
    assert rrd.times(lay.BARO_PRESSURE) == [7000]
    assert rrd.timelines[lay.BARO_PRESSURE] == {lay.SIM_TIME}


def test_pose_trail_and_setpoint_marker_at_the_pose_rate(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=50.0, pose_rate_hz=20.0)
    q = from_euler(0.2, 0.0, 0.5)
    for k in range(1, 251):
        t = 4000 * k
        logger.log_message("sim_groundtruth", 0, SimGroundtruth(timestamp=t, position=(0.004 * k, 0.0, -1.0)))
        logger.log_message("vehicle_attitude", 0, VehicleAttitude(timestamp=t, q=q))
        logger.log_message("vehicle_local_position", 0, VehicleLocalPosition(timestamp=t, x=0.004 * k, z=-1.0))
        position = (1.0, 2.0, -3.0) if k > 125 else (NAN, NAN, NAN)
        logger.log_message("trajectory_setpoint", 0, TrajectorySetpoint(timestamp=t, position=position))
    close(logger)
    rrd = read_rrd(path)
    buckets = 21  # 50 ms buckets from t = 4 ms to 1 s: 0..20
    assert rrd.rows(lay.VEHICLE) == buckets
    assert rrd.rows(lay.TRAIL_ESTIMATE) == buckets - 1
    assert rrd.rows(lay.TRAIL_TRUTH) == buckets - 1
    first_segment = rrd.values(lay.TRAIL_ESTIMATE, "LineStrips3D:strips")[0][0]
    assert first_segment == [pytest.approx([0.004, 0.0, -1.0]), pytest.approx([0.06, 0.0, -1.0])]
    # The last pose, at t = 1 s, uses the estimate received before it (t = 0.996 s).
    assert rrd.values(lay.VEHICLE, "Transform3D:translation")[-1] == [pytest.approx([0.996, 0.0, -1.0])]
    assert rrd.values(lay.VEHICLE, "Transform3D:quaternion")[0] == [pytest.approx([q[1], q[2], q[3], q[0]])]  # xyzw
    markers = rrd.values(lay.SETPOINT_MARKER, "Points3D:positions")
    assert len(markers) == buckets
    assert markers[0] == [] and markers[-1] == [pytest.approx([1.0, 2.0, -3.0])]


def test_flush_period_batches_by_data_time_or_leaves_it_to_the_caller(tmp_path):
    logger, _ = open_logger(tmp_path, plot_rate_hz=0.0, flush_period_s=0.1)
    for k in range(1, 251):
        logger.log_message("sensor_baro", 0, SensorBaro(timestamp=4000 * k))
    assert 9 <= logger.flushes <= 10
    assert logger.chunks_sent == logger.flushes
    close(logger)

    logger, _ = open_logger(tmp_path, "manual", plot_rate_hz=0.0, flush_period_s=0.0)
    for k in range(1, 251):
        logger.log_message("sensor_baro", 0, SensorBaro(timestamp=4000 * k))
    assert logger.chunks_sent == 0
    logger.flush()
    assert (logger.flushes, logger.chunks_sent) == (1, 1)
    close(logger)


def test_unknown_topics_and_other_instances_are_ignored(tmp_path):
    logger, path = open_logger(tmp_path)
    assert not logger.log_message("sensor_gyro", 0, SensorBaro(timestamp=1000))
    assert not logger.log_message("sensor_baro", 1, SensorBaro(timestamp=1000))
    assert logger.log_message("sensor_baro", 0, SensorBaro(timestamp=1000))
    close(logger)
    assert read_rrd(path).rows(lay.BARO_PRESSURE) == 1


def test_vehicle_geometry_mission_and_home(tmp_path):
    hexa = [(0.3 * math.cos(a * math.pi / 3), 0.3 * math.sin(a * math.pi / 3), 0.0) for a in range(6)]
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0, rotors=hexa)
    logger.log_message("actuator_motors", 0, ActuatorMotors(timestamp=1000, control=(0.5,) * 6 + (NAN,) * 6))
    logger.log_message("sensor_baro", 0, SensorBaro(timestamp=2_000_000))
    logger.log_mission([(0.0, 0.0, -10.0), (20.0, 0.0, -10.0)], home=(1.0, 1.0, 0.0))
    close(logger)
    rrd = read_rrd(path)
    assert len(rrd.static[lay.VEHICLE_ARMS]["LineStrips3D:strips"]) == 6
    assert len(rrd.static[lay.VEHICLE_ROTORS]["LineStrips3D:strips"]) == 6
    assert len(rrd.static[lay.MOTOR_COMMANDS]["SeriesLines:names"]) == 6
    assert rrd.values(lay.MOTOR_COMMANDS) == [[0.5] * 6]
    assert rrd.values(lay.MISSION_WAYPOINTS, "Points3D:labels") == [["1", "2"]]
    path_strip = rrd.values(lay.MISSION_PATH, "LineStrips3D:strips")[0][0]
    assert path_strip == [[1.0, 1.0, 0.0], [0.0, 0.0, -10.0], [20.0, 0.0, -10.0]]
    assert rrd.times(lay.MISSION_WAYPOINTS) == [2_000_000]
    homes = rrd.temporal[lay.HOME]
    assert [t for t, _ in homes] == [0, 2_000_000]
    assert homes[0][1]["Points3D:positions"] == [[0.0, 0.0, 0.0]]
    assert homes[1][1]["Points3D:positions"] == [[1.0, 1.0, 0.0]]


def test_generic_quad_without_rotor_geometry(tmp_path):
    logger, path = open_logger(tmp_path)
    close(logger)
    rrd = read_rrd(path)
    assert len(rrd.static[lay.VEHICLE_ARMS]["LineStrips3D:strips"]) == 4
    assert rrd.static[lay.WORLD]


def test_rejects_nonsense_rates(tmp_path):
    rec = new_recording("bad")
    with pytest.raises(ValueError):
        FlightLogger(rec, plot_rate_hz=-1.0)
    with pytest.raises(ValueError):
        FlightLogger(rec, pose_rate_hz=0.0)


def test_mission_and_home_topics_are_drawn_about_home(tmp_path):
    logger, path = open_logger(tmp_path, plot_rate_hz=0.0)
    items = [
        MissionItemEntry(command=22, down=-10.0),  # takeoff where the vehicle is: not drawn
        MissionItemEntry(north=20.0, east=0.0, down=-10.0),
        MissionItemEntry(north=20.0, east=20.0, down=-10.0),
    ]
    assert logger.log_message("mission", 0, Mission(timestamp=1_000_000, items=items))
    home = HomePosition(timestamp=3_000_000, x=2.0, y=-1.0, z=0.5, valid_lpos=True)
    assert logger.log_message("home_position", 0, home)
    assert logger.log_message("home_position", 0, HomePosition(timestamp=4_000_000, x=9.0, valid_lpos=False))
    close(logger)
    rrd = read_rrd(path)
    assert rrd.times(lay.MISSION_WAYPOINTS) == [1_000_000, 3_000_000]
    assert rrd.values(lay.MISSION_WAYPOINTS, "Points3D:positions")[-1] == [[22.0, -1.0, -9.5], [22.0, 19.0, -9.5]]
    assert rrd.values(lay.MISSION_PATH, "LineStrips3D:strips")[-1][0][0] == [2.0, -1.0, 0.5]
    homes = rrd.temporal[lay.HOME]
    assert [h[1]["Points3D:positions"] for h in homes][-1] == [[2.0, -1.0, 0.5]]
    assert [t for t, _ in homes][-1] == 3_000_000
