"""MAVLink ↔ stack message mapping (stack.pixhawk.convert): units, frames, validity flags, refusals.

Inbound messages go through a real MAVLink 2 encode and parse first, so field names and wire types are
pymavlink's own.
"""

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import BatteryStatus
from stack.pixhawk import convert

MAV = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
ALL_IMU = 0x1FFF
UINT16_MAX = 0xFFFF
NAN = math.nan


def wire(msg: mavlink2.MAVLink_message) -> mavlink2.MAVLink_message:
    """The message as the adapter receives it: packed into a MAVLink 2 frame and parsed back."""
    (parsed,) = MAV.parse_buffer(msg.pack(MAV))
    return parsed


def imu(fields_updated: int = ALL_IMU, **changes: float) -> mavlink2.MAVLink_message:
    values = dict(
        time_usec=5_000_000,
        xacc=0.1,
        yacc=-0.2,
        zacc=-9.8,
        xgyro=0.01,
        ygyro=-0.02,
        zgyro=0.03,
        xmag=0.21,
        ymag=0.01,
        zmag=0.42,
        abs_pressure=1013.25,
        diff_pressure=0.0,
        pressure_alt=0.0,
        temperature=25.0,
        fields_updated=fields_updated,
    )
    values.update(changes)
    return wire(mavlink2.MAVLink_highres_imu_message(**values))


# -- HIGHRES_IMU ---------------------------------------------------------------------------------------


def test_highres_imu_gives_every_sensor_in_si_units_accelerometer_before_gyro():
    out, refused = convert.highres_imu(imu(), 123_456, device_id=7)
    assert refused == []
    assert [topic.name for topic, _ in out] == ["sensor_accel", "sensor_gyro", "sensor_mag", "sensor_baro"]
    msgs = dict(out)
    accel, gyro, mag, baro = (
        msgs[t] for t in (ORB_ID.sensor_accel, ORB_ID.sensor_gyro, ORB_ID.sensor_mag, ORB_ID.sensor_baro)
    )
    assert (accel.x, accel.y, accel.z) == pytest.approx((0.1, -0.2, -9.8))
    assert (gyro.x, gyro.y, gyro.z) == pytest.approx((0.01, -0.02, 0.03))
    assert (mag.x, mag.y, mag.z) == pytest.approx((0.21, 0.01, 0.42))  # gauss, as sensor_mag wants
    assert baro.pressure == pytest.approx(101_325.0)  # hPa → Pa
    assert gyro.temperature == pytest.approx(25.0) and baro.temperature == pytest.approx(25.0)
    assert all(m.timestamp_sample == 123_456 and m.device_id == 7 for _, m in out)


def test_highres_imu_publishes_only_what_fields_updated_marks_new():
    gyro_only = mavlink2.HIGHRES_IMU_UPDATED_XGYRO | mavlink2.HIGHRES_IMU_UPDATED_YGYRO
    gyro_only |= mavlink2.HIGHRES_IMU_UPDATED_ZGYRO
    out, _ = convert.highres_imu(imu(gyro_only), 1, 1)
    assert [topic.name for topic, _ in out] == ["sensor_gyro"]
    assert math.isnan(out[0][1].temperature)  # temperature not updated: unknown
    out, _ = convert.highres_imu(imu(mavlink2.HIGHRES_IMU_UPDATED_XGYRO), 1, 1)
    assert out == []  # one axis alone is not a sample
    out, _ = convert.highres_imu(imu(mavlink2.HIGHRES_IMU_UPDATED_ABS_PRESSURE), 1, 1)
    assert [topic.name for topic, _ in out] == ["sensor_baro"]


@pytest.mark.parametrize(
    ("change", "refused_topic"),
    [
        ({"xgyro": NAN}, "sensor_gyro"),
        ({"zgyro": 1e6}, "sensor_gyro"),
        ({"yacc": math.inf}, "sensor_accel"),
        ({"xmag": 100.0}, "sensor_mag"),
        ({"abs_pressure": 0.0}, "sensor_baro"),
    ],
)
def test_a_corrupt_imu_value_refuses_that_sensor_only(change, refused_topic):
    out, refused = convert.highres_imu(imu(**change), 1, 1)
    assert len(refused) == 1 and refused[0]
    topics = [topic.name for topic, _ in out]
    assert refused_topic not in topics and len(topics) == 3


# -- GPS_RAW_INT ---------------------------------------------------------------------------------------


def gps(**changes: int) -> mavlink2.MAVLink_message:
    values = dict(
        time_usec=9_000_000,
        fix_type=3,
        lat=473_977_420,
        lon=85_455_940,
        alt=488_000,
        eph=70,
        epv=110,
        vel=200,
        cog=9000,
        satellites_visible=12,
        alt_ellipsoid=535_000,
        h_acc=900,
        v_acc=1500,
        vel_acc=300,
        hdg_acc=0,
        yaw=0,
    )
    values.update(changes)
    return wire(mavlink2.MAVLink_gps_raw_int_message(**values))


def test_gps_raw_int_units_and_accuracies():
    g = convert.gps_raw_int(gps(), 42, 3)
    assert (g.latitude_deg, g.longitude_deg) == pytest.approx((47.397742, 8.545594))
    assert g.altitude_msl_m == pytest.approx(488.0) and g.altitude_ellipsoid_m == pytest.approx(535.0)
    assert (g.eph, g.epv, g.hdop, g.vdop) == pytest.approx((0.9, 1.5, 0.7, 1.1))
    assert g.s_variance_m_s == pytest.approx(0.3)
    assert g.fix_type == 3 and g.satellites_used == 12 and g.timestamp_sample == 42 and g.device_id == 3
    # 2 m/s on course 90°: due east; no vertical velocity, so the NED velocity is not marked valid.
    assert (g.vel_m_s, g.vel_n_m_s, g.vel_e_m_s) == pytest.approx((2.0, 0.0, 2.0), abs=1e-9)
    assert math.isnan(g.vel_d_m_s) and g.vel_ned_valid is False
    assert g.cog_rad == pytest.approx(math.pi / 2)
    assert g.time_utc_usec == 0  # time since boot, not UNIX time


def test_gps_raw_int_unknowns():
    g = convert.gps_raw_int(gps(eph=UINT16_MAX, epv=UINT16_MAX, h_acc=0, v_acc=0, vel_acc=0, alt_ellipsoid=0), 1, 1)
    assert math.isnan(g.hdop) and math.isnan(g.eph) and math.isnan(g.epv) and math.isnan(g.s_variance_m_s)
    assert g.altitude_ellipsoid_m == pytest.approx(488.0)
    g = convert.gps_raw_int(gps(vel=UINT16_MAX, cog=UINT16_MAX), 1, 1)
    assert math.isnan(g.vel_n_m_s) and math.isnan(g.vel_e_m_s)
    unix = convert.gps_raw_int(gps(time_usec=1_700_000_000_000_000), 1, 1)
    assert unix.time_utc_usec == 1_700_000_000_000_000 and convert.is_unix_time(unix.time_utc_usec)
    with pytest.raises(convert.Refused):
        convert.gps_raw_int(gps(lat=1_000_000_000), 1, 1)


# -- battery -------------------------------------------------------------------------------------------


def battery(**changes) -> mavlink2.MAVLink_message:
    values = dict(
        id=0,
        battery_function=mavlink2.MAV_BATTERY_FUNCTION_ALL,
        type=mavlink2.MAV_BATTERY_TYPE_LIPO,
        temperature=2550,
        voltages=[4000, 4000, 4000, 4000] + [UINT16_MAX] * 6,
        current_battery=1234,
        current_consumed=321,
        energy_consumed=-1,
        battery_remaining=64,
        time_remaining=600,
        charge_state=mavlink2.MAV_BATTERY_CHARGE_STATE_OK,
    )
    values.update(changes)
    return wire(mavlink2.MAVLink_battery_status_message(**values))


def test_battery_status_sums_the_cells_and_maps_the_charge_state():
    b = convert.battery_status(battery())
    assert b.connected and b.cell_count == 4
    assert b.voltage_v == pytest.approx(16.0) and b.current_a == pytest.approx(12.34)
    assert b.remaining == pytest.approx(0.64) and b.discharged_mah == 321.0
    assert b.temperature == pytest.approx(25.5) and b.time_remaining_s == 600.0
    assert b.warning == BatteryStatus.WARNING_NONE
    low = convert.battery_status(battery(charge_state=mavlink2.MAV_BATTERY_CHARGE_STATE_CRITICAL))
    assert low.warning == BatteryStatus.WARNING_CRITICAL
    pack = convert.battery_status(
        battery(voltages=[15800] + [UINT16_MAX] * 9, current_battery=-1, battery_remaining=-1)
    )
    assert pack.voltage_v == pytest.approx(15.8) and pack.cell_count == 0  # the whole pack in cell 0
    assert pack.current_a == -1.0 and pack.remaining == -1.0


def sys_status(present: int, health: int, voltage: int = 15800) -> mavlink2.MAVLink_message:
    return wire(mavlink2.MAVLink_sys_status_message(present, present, health, 0, voltage, 500, 80, 0, 0, 0, 0, 0, 0))


def test_sys_status_battery_and_prearm_bit():
    prearm = mavlink2.MAV_SYS_STATUS_PREARM_CHECK
    b = convert.sys_status_battery(sys_status(prearm, prearm))
    assert (
        b.voltage_v == pytest.approx(15.8) and b.current_a == pytest.approx(5.0) and b.remaining == pytest.approx(0.8)
    )
    assert convert.prearm_ok(sys_status(prearm, prearm)) is True
    assert convert.prearm_ok(sys_status(prearm, 0)) is False
    assert convert.prearm_ok(sys_status(0, 0)) is None  # not reported
    assert convert.sys_status_battery(sys_status(0, 0, voltage=UINT16_MAX)).voltage_v == 0.0


# -- the autopilot's estimate --------------------------------------------------------------------------

Q30 = quat.from_euler(0.1, -0.2, math.radians(30.0))


def test_attitude_quaternion_is_hamilton_body_to_ned():
    msg = wire(mavlink2.MAVLink_attitude_quaternion_message(1000, *Q30, 0.1, 0.2, 0.3))
    att, rates = convert.attitude_quaternion(msg, 99)
    assert att.q == pytest.approx(Q30, abs=1e-6) and att.timestamp_sample == 99
    assert rates.xyz == pytest.approx((0.1, 0.2, 0.3)) and rates.timestamp_sample == 99
    with pytest.raises(convert.Refused, match="unit quaternion"):
        convert.attitude_quaternion(wire(mavlink2.MAVLink_attitude_quaternion_message(1, 2, 0, 0, 0, 0, 0, 0)), 1)
    with pytest.raises(convert.Refused):
        convert.attitude_quaternion(wire(mavlink2.MAVLink_attitude_quaternion_message(1, NAN, 0, 0, 0, 0, 0, 0)), 1)


def test_local_position_ned_is_valid_with_unreported_accuracy():
    origin = convert.gps_global_origin(
        wire(mavlink2.MAVLink_gps_global_origin_message(473_977_420, 85_455_940, 488_000))
    )
    lpos = convert.local_position_ned(
        wire(mavlink2.MAVLink_local_position_ned_message(0, 1, 2, -3, 0.1, 0.2, -0.3)), 5, origin
    )
    assert (lpos.x, lpos.y, lpos.z, lpos.vx, lpos.vy, lpos.vz) == pytest.approx((1, 2, -3, 0.1, 0.2, -0.3))
    assert lpos.xy_valid and lpos.z_valid and lpos.v_xy_valid and lpos.v_z_valid
    assert math.isnan(lpos.eph) and math.isnan(lpos.epv)  # not INF: that would fail every position check
    assert (lpos.ref_lat, lpos.ref_lon, lpos.ref_alt) == pytest.approx((47.397742, 8.545594, 488.0))
    assert lpos.xy_global and lpos.z_global
    unreferenced = convert.local_position_ned(
        wire(mavlink2.MAVLink_local_position_ned_message(0, 0, 0, 0, 0, 0, 0)), 5, convert.LocalOrigin()
    )
    assert not unreferenced.xy_global and math.isnan(unreferenced.ref_lat)


def odometry(child: int = mavlink2.MAV_FRAME_BODY_FRD, frame: int = mavlink2.MAV_FRAME_LOCAL_NED, var: float = 0.25):
    covariance = [NAN] * 21
    covariance[0] = covariance[6] = var
    covariance[11] = 4 * var
    return wire(
        mavlink2.MAVLink_odometry_message(
            7, frame, child, 1.0, 2.0, -3.0, list(Q30), 1.0, 0.0, 0.0, 0, 0, 0, covariance, [NAN] * 21
        )
    )


def test_odometry_rotates_body_velocity_and_reads_the_covariance():
    att, lpos = convert.odometry(odometry(), 3, convert.LocalOrigin())
    assert att.q == pytest.approx(Q30, abs=1e-6)
    assert (lpos.vx, lpos.vy, lpos.vz) == pytest.approx(quat.rotate(Q30, (1.0, 0.0, 0.0)), abs=1e-6)
    assert (lpos.eph, lpos.epv) == pytest.approx((0.5, 1.0))
    assert lpos.heading == pytest.approx(math.radians(30.0)) and lpos.heading_good_for_control
    _, ned = convert.odometry(odometry(child=mavlink2.MAV_FRAME_LOCAL_NED), 3, convert.LocalOrigin())
    assert (ned.vx, ned.vy, ned.vz) == pytest.approx((1.0, 0.0, 0.0))
    with pytest.raises(convert.Refused, match="frame_id"):
        convert.odometry(odometry(frame=mavlink2.MAV_FRAME_BODY_FRD), 3, convert.LocalOrigin())


# -- SIM_STATE -----------------------------------------------------------------------------------------

HOME = (47.397742, 8.545594, 488.0)


def sim_state(north: float, east: float, down: float, q=quat.IDENTITY, velocity=(0.0, 0.0, 0.0), specific_force=None):
    lat, lon = MapProjection(HOME[0], HOME[1]).reproject(north, east)
    force = specific_force or quat.rotate_inv(q, (0.0, 0.0, -CONSTANTS_ONE_G))
    roll, pitch, yaw = quat.to_euler(q)
    return wire(
        mavlink2.MAVLink_sim_state_message(
            *q, roll, pitch, yaw, *force, 0.1, 0.2, 0.3, lat, lon, HOME[2] - down, 0, 0, *velocity,
            round(lat * 1e7), round(lon * 1e7),
        )
    )  # fmt: skip


def test_sim_state_is_the_truth_in_ned_about_the_first_position():
    frame = convert.TruthFrame()
    start = frame.convert(sim_state(0.0, 0.0, 0.0), 10)
    assert start.position == pytest.approx((0.0, 0.0, 0.0), abs=1e-9) and start.on_ground
    assert start.acceleration == pytest.approx((0.0, 0.0, 0.0), abs=1e-5)  # at rest: specific force −g
    flying = frame.convert(sim_state(10.0, -5.0, -4.0, q=Q30, velocity=(1.0, 0.5, -0.2)), 20)
    assert flying.position == pytest.approx((10.0, -5.0, -4.0), abs=0.02)  # degE7: about 1 cm
    assert flying.velocity == pytest.approx((1.0, 0.5, -0.2)) and flying.q == pytest.approx(Q30, abs=1e-6)
    assert flying.angular_velocity == pytest.approx((0.1, 0.2, 0.3)) and flying.timestamp_sample == 20
    assert flying.acceleration == pytest.approx((0.0, 0.0, 0.0), abs=1e-4) and not flying.on_ground
    with pytest.raises(convert.Refused):
        frame.convert(sim_state(0.0, 0.0, 0.0, q=(0.5, 0.0, 0.0, 0.0)), 30)


# -- outbound ------------------------------------------------------------------------------------------


def test_rates_setpoint_becomes_body_rates_and_collective_thrust():
    t = convert.rates_target(VehicleRatesSetpoint(roll=0.1, pitch=-0.2, yaw=0.3, thrust_body=(0.0, 0.0, -0.55)))
    assert t.type_mask == mavlink2.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE
    assert (t.body_roll_rate, t.body_pitch_rate, t.body_yaw_rate) == (0.1, -0.2, 0.3)
    assert t.thrust == pytest.approx(0.55)
    # It survives the wire as PX4 reads it.
    msg = wire(mavlink2.MAVLink_set_attitude_target_message(0, 1, 1, t.type_mask, t.q, 0.1, -0.2, 0.3, t.thrust))
    assert msg.type_mask == 128 and msg.thrust == pytest.approx(0.55)


@pytest.mark.parametrize(
    "setpoint",
    [
        VehicleRatesSetpoint(roll=NAN, thrust_body=(0.0, 0.0, -0.5)),
        VehicleRatesSetpoint(yaw=math.inf, thrust_body=(0.0, 0.0, -0.5)),
        VehicleRatesSetpoint(pitch=100.0, thrust_body=(0.0, 0.0, -0.5)),
        VehicleRatesSetpoint(thrust_body=(0.0, 0.0, NAN)),
        VehicleRatesSetpoint(thrust_body=(0.0, 0.0, 0.5)),
        VehicleRatesSetpoint(thrust_body=(0.0, 0.0, -1.5)),
    ],
)
def test_a_nan_or_out_of_range_setpoint_is_refused_never_sent(setpoint):
    with pytest.raises(convert.Refused):
        convert.rates_target(setpoint)


def test_attitude_setpoint_becomes_attitude_and_thrust():
    t = convert.attitude_target(VehicleAttitudeSetpoint(q_d=Q30, thrust_body=(0.0, 0.0, -0.4)))
    assert t.type_mask == 7 and t.q == pytest.approx(Q30) and t.thrust == pytest.approx(0.4)
    with pytest.raises(convert.Refused):
        convert.attitude_target(VehicleAttitudeSetpoint(q_d=(NAN, 0.0, 0.0, 0.0), thrust_body=(0.0, 0.0, -0.4)))
    with pytest.raises(convert.Refused):
        convert.attitude_target(VehicleAttitudeSetpoint(q_d=(2.0, 0.0, 0.0, 0.0), thrust_body=(0.0, 0.0, -0.4)))
    assert convert.IDLE_TARGET.thrust == 0.0 and convert.IDLE_TARGET.type_mask == convert.RATES_TYPE_MASK


# -- STATUSTEXT ----------------------------------------------------------------------------------------


def test_statustext_chunks_are_reassembled():
    text = "Switching to OFFBOARD is currently not possible: no offboard signal"
    assembler = convert.StatustextAssembler()
    chunks = [text[i : i + 50] for i in range(0, len(text), 50)]
    msgs = [wire(mavlink2.MAVLink_statustext_message(2, c.encode(), 7, i)) for i, c in enumerate(chunks)]
    assert assembler.add(msgs[0].text, msgs[0].id, msgs[0].chunk_seq) is None
    assert assembler.add(msgs[1].text, msgs[1].id, msgs[1].chunk_seq) == text
    assert assembler.add(b"Armed\0\0", 0, 0) == "Armed"
    for i in range(10):  # unfinished texts are not kept forever
        assembler.add("x" * 50, 100 + i, 0)
    assert len(assembler._parts) <= convert.STATUSTEXT_PENDING
