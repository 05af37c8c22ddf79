"""The telemetry builders: the stack's topics in MAVLink's units, nothing without data."""

import math

import pytest
from pymavlink.dialects.v20 import common as M

from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mavlink import telemetry as T
from stack.msg.estimation import EstimatorStatus, VehicleImuStatus, VehicleLocalPosition
from stack.msg.sensors import SensorBaro, SensorGps, SensorMag
from stack.msg.system import BatteryStatus, HomePosition, VehicleControlMode, VehicleLandDetected
from stack.msg.system import VehicleStatus as NS

NOW = 50_000_000
REF = (47.397742, 8.545594, 489.4)


def _view(**changes) -> T.VehicleView:
    view = T.VehicleView(
        status=NS(timestamp=NOW, nav_state=NS.NAVIGATION_STATE_AUTO_LOITER, pre_flight_checks_pass=True),
        control_mode=VehicleControlMode(
            timestamp=NOW, flag_armed=True, flag_control_rates_enabled=True, flag_control_attitude_enabled=True
        ),
        land=VehicleLandDetected(timestamp=NOW, landed=False),
        home=HomePosition(
            timestamp=NOW,
            lat=REF[0],
            lon=REF[1],
            alt=REF[2],
            z=0.5,
            yaw=0.3,
            valid_hpos=True,
            valid_alt=True,
            valid_lpos=True,
        ),
        local_position=VehicleLocalPosition(
            timestamp=NOW,
            xy_valid=True,
            z_valid=True,
            v_xy_valid=True,
            x=10.0,
            y=-20.0,
            z=-5.0,
            vx=1.0,
            vy=-2.0,
            vz=-0.5,
            heading=math.radians(90.0),
            ref_lat=REF[0],
            ref_lon=REF[1],
            ref_alt=REF[2],
        ),
        estimator=EstimatorStatus(
            timestamp=NOW,
            attitude_valid=True,
            attitude_timestamp=NOW,
            q=quat.from_euler(0.1, -0.2, 1.0),
            gyro_bias=(0.01, 0.0, 0.0),
        ),
        imu=VehicleImuStatus(timestamp=NOW, gyro_rate_hz=250.0, accel_rate_hz=250.0, mean_gyro=(0.11, 0.2, -0.3)),
        gps=SensorGps(
            timestamp=NOW,
            latitude_deg=47.4,
            longitude_deg=8.5,
            altitude_msl_m=500.0,
            fix_type=3,
            hdop=0.7,
            vdop=1.1,
            eph=0.8,
            epv=1.2,
            vel_m_s=2.0,
            cog_rad=math.radians(45.0),
            vel_ned_valid=True,
            satellites_used=12,
        ),
        battery=BatteryStatus(
            timestamp=NOW,
            connected=True,
            voltage_v=16.0,
            current_a=12.5,
            remaining=0.834,
            cell_count=4,
            discharged_mah=300.0,
        ),
        mag=SensorMag(timestamp=NOW),
        baro=SensorBaro(timestamp=NOW),
    )
    for name, value in changes.items():
        setattr(view, name, value)
    return view


def test_global_position_is_the_local_one_placed_about_its_reference():
    msg = T.global_position_int(_view(), NOW)
    lat, lon = MapProjection(REF[0], REF[1]).reproject(10.0, -20.0)
    assert (msg.lat, msg.lon) == (round(lat * 1e7), round(lon * 1e7))
    assert msg.alt == round((REF[2] + 5.0) * 1000) and msg.relative_alt == 5500
    assert (msg.vx, msg.vy, msg.vz, msg.hdg) == (100, -200, -50, 9000)
    assert msg.time_boot_ms == NOW // 1000


def test_no_position_no_global_or_local_position():
    stale = _view(local_position=VehicleLocalPosition(timestamp=NOW - 2_000_000, xy_valid=True, z_valid=True))
    assert T.global_position_int(stale, NOW) is None and T.local_position_ned(stale, NOW) is None
    no_ref = _view(local_position=VehicleLocalPosition(timestamp=NOW, xy_valid=True, z_valid=True))
    assert T.global_position_int(no_ref, NOW) is None and T.local_position_ned(no_ref, NOW) is not None
    assert T.global_position_int(_view(local_position=None), NOW) is None


def test_attitude_in_euler_and_quaternion_with_bias_corrected_rates():
    att = T.attitude(_view(), NOW)
    assert (att.roll, att.pitch, att.yaw) == pytest.approx((0.1, -0.2, 1.0), abs=1e-6)
    assert (att.rollspeed, att.pitchspeed, att.yawspeed) == pytest.approx((0.1, 0.2, -0.3), abs=1e-6)
    q = T.attitude_quaternion(_view(), NOW)
    assert (q.q1, q.q2, q.q3, q.q4) == pytest.approx(quat.from_euler(0.1, -0.2, 1.0), abs=1e-6)
    invalid = _view(estimator=EstimatorStatus(timestamp=NOW, attitude_valid=False))
    assert T.attitude(invalid, NOW) is None and T.attitude_quaternion(invalid, NOW) is None


def test_gps_in_mavlink_units():
    g = T.gps_raw_int(_view(), NOW)
    assert (g.fix_type, g.lat, g.lon, g.alt) == (3, 474_000_000, 85_000_000, 500_000)
    assert (g.eph, g.epv, g.vel, g.cog, g.satellites_visible) == (70, 110, 200, 4500, 12)
    assert (g.h_acc, g.v_acc) == (800, 1200)
    unknown = T.gps_raw_int(_view(gps=SensorGps(timestamp=NOW)), NOW)
    assert (unknown.eph, unknown.epv, unknown.cog) == (0xFFFF, 0xFFFF, 0xFFFF)


def test_home_and_its_heading():
    h = T.home_position(_view(), NOW)
    assert (h.latitude, h.longitude, h.altitude, h.z) == (round(REF[0] * 1e7), round(REF[1] * 1e7), 489400, 0.5)
    assert quat.yaw(tuple(h.q)) == pytest.approx(0.3)
    assert T.home_position(_view(home=HomePosition(timestamp=NOW)), NOW) is None


@pytest.mark.parametrize(
    ("landed", "nav_state", "state"),
    [
        (True, NS.NAVIGATION_STATE_AUTO_TAKEOFF, M.MAV_LANDED_STATE_ON_GROUND),
        (False, NS.NAVIGATION_STATE_AUTO_TAKEOFF, M.MAV_LANDED_STATE_TAKEOFF),
        (False, NS.NAVIGATION_STATE_AUTO_LAND, M.MAV_LANDED_STATE_LANDING),
        (False, NS.NAVIGATION_STATE_DESCEND, M.MAV_LANDED_STATE_LANDING),
        (False, NS.NAVIGATION_STATE_AUTO_RTL, M.MAV_LANDED_STATE_IN_AIR),
    ],
)
def test_landed_state_from_the_land_detector_and_the_mode(landed, nav_state, state):
    view = _view(land=VehicleLandDetected(landed=landed), status=NS(nav_state=nav_state))
    assert T.extended_sys_state(view, NOW).landed_state == state


def test_prearm_check_health_follows_the_commanders_pre_arm_checks():
    present, enabled, health = T.sensor_bits(_view(), NOW)
    prearm = M.MAV_SYS_STATUS_PREARM_CHECK
    assert present & prearm and enabled & prearm and health & prearm
    _, _, failing = T.sensor_bits(_view(status=NS(pre_flight_checks_pass=False)), NOW)
    assert not failing & prearm


def test_sensor_health_needs_fresh_data_and_gps_a_3d_fix():
    sensors = T.SENSOR_BITS
    present, enabled, health = T.sensor_bits(_view(), NOW)
    assert present & sensors == sensors and enabled & sensors == sensors and health & sensors == sensors
    assert health & M.MAV_SYS_STATUS_AHRS
    later = NOW + 2_000_000
    present, _, health = T.sensor_bits(_view(), later)
    assert present & sensors == sensors and not health & sensors and not health & M.MAV_SYS_STATUS_AHRS
    _, _, no_fix = T.sensor_bits(_view(gps=SensorGps(timestamp=NOW, fix_type=2)), NOW)
    assert not no_fix & M.MAV_SYS_STATUS_SENSOR_GPS
    present, _, _ = T.sensor_bits(_view(mag=None, baro=None, gps=None), NOW)
    assert not present & (M.MAV_SYS_STATUS_SENSOR_3D_MAG | M.MAV_SYS_STATUS_SENSOR_GPS)


def test_control_bits_are_enabled_by_the_control_mode():
    _, enabled, _ = T.sensor_bits(_view(), NOW)
    assert enabled & M.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL and enabled & M.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    assert not enabled & M.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL


def test_battery_in_sys_status_and_battery_status():
    s = T.sys_status(_view(), NOW, drop_rate_comm=0.25, errors_comm=3)
    assert (s.voltage_battery, s.current_battery, s.battery_remaining) == (16000, 1250, 84)
    assert (s.drop_rate_comm, s.errors_comm) == (2500, 3)
    b = T.battery_status(_view(), NOW)
    assert list(b.voltages[:5]) == [4000, 4000, 4000, 4000, 0xFFFF]
    assert (b.current_battery, b.current_consumed, b.battery_remaining) == (1250, 300, 84)
    assert b.charge_state == M.MAV_BATTERY_CHARGE_STATE_OK and b.temperature == 0x7FFF
    none = T.sys_status(_view(battery=None), NOW)
    assert (none.voltage_battery, none.current_battery, none.battery_remaining) == (0xFFFF, -1, -1)
    assert T.battery_status(_view(battery=None), NOW) is None


def test_vfr_hud_has_ground_speed_heading_altitude_and_climb():
    hud = T.vfr_hud(_view(), NOW)
    assert (hud.groundspeed, hud.heading, hud.climb) == pytest.approx((math.sqrt(5.0), 90, 0.5))
    assert hud.alt == pytest.approx(REF[2] + 5.0) and (hud.airspeed, hud.throttle) == (0.0, 0)


def test_every_message_packs():
    mav = M.MAVLink(None, 1, 1)
    view = _view()
    for build in (
        T.attitude,
        T.attitude_quaternion,
        T.global_position_int,
        T.local_position_ned,
        T.gps_raw_int,
        T.home_position,
        T.extended_sys_state,
        T.vfr_hud,
        T.battery_status,
        T.sys_status,
    ):
        msg = build(view, NOW)
        assert mav.decode(bytearray(msg.pack(mav))).get_type() == msg.get_type()
