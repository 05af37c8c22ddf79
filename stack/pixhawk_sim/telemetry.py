"""The simulated Pixhawk's telemetry: one MAVLink message per stream, built from its state now.

Field by field as PX4's ``src/modules/mavlink/streams/*.hpp`` fill them, in MAVLink units (common.xml).
The Pixhawk's "estimate" (ATTITUDE, LOCAL_POSITION_NED, ODOMETRY, GLOBAL_POSITION_INT...) is the simulator's
truth, with the body rates of its gyro pipeline; the raw sensors (HIGHRES_IMU, SCALED_PRESSURE, GPS_RAW_INT)
are the simulated sensors' samples, stamped with the autopilot's boot time of the measurement.

SIM_STATE carries the truth for judging a flight. The vehicle's NED position about the origin (the simulator's
home, which GPS_GLOBAL_ORIGIN gives) is in ``lat_int``/``lon_int`` (degE7, MAVLink 2 extension; the float
``lat``/``lon`` in degrees have only ~0.4 m resolution) and ``alt`` (m AMSL): north, east =
``MapProjection(origin).project(lat_int·1e-7, lon_int·1e-7)``, down = origin altitude − ``alt``. ``vn``/``ve``/``vd``
are the NED velocity, ``q1..q4`` the attitude (w, x, y, z, body FRD → NED), ``x/y/zgyro`` the true body rates,
``x/y/zacc`` the true specific force in FRD, and ``std_dev_horz``/``std_dev_vert`` 0 (it is the truth).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from pymavlink.dialects.v20 import common as mavlink

from stack.mathlib import quaternion as quat
from stack.mathlib.atmosphere import isa_altitude_m
from stack.mavlink import px4_modes
from stack.mavlink.telemetry import (
    attitude_message,
    attitude_quaternion_message,
    battery_current_ca,
    battery_remaining_pct,
    battery_status_message,
    cdeg,
    deg_e7,
    extended_sys_state_message,
    landed_state_of,
    local_position_ned_message,
    time_boot_ms,
)
from stack.msg.system import BatteryStatus
from stack.pixhawk_sim.vehicle import SimulatedPixhawk
from stack.sim.sensors import BaroSample, GpsSample, ImuSample, MagSample

Message = mavlink.MAVLink_message

PX4_VERSION_MODELLED = (1, 16, 0)
"""The PX4 release whose behaviour is modelled (upstream main after v1.16), reported in AUTOPILOT_VERSION."""
CAPABILITIES = (
    mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    | mavlink.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET
    | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
)
SENSORS = (
    mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | mavlink.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mavlink.MAV_SYS_STATUS_SENSOR_3D_MAG
    | mavlink.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | mavlink.MAV_SYS_STATUS_SENSOR_GPS
    | mavlink.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | mavlink.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    | mavlink.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | mavlink.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    | mavlink.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    | mavlink.MAV_SYS_STATUS_AHRS
    | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
)
"""SYS_STATUS sensors present, enabled and healthy (the simulated ones never fail)."""
_IMU_FIELDS = (
    mavlink.HIGHRES_IMU_UPDATED_XACC
    | mavlink.HIGHRES_IMU_UPDATED_YACC
    | mavlink.HIGHRES_IMU_UPDATED_ZACC
    | mavlink.HIGHRES_IMU_UPDATED_XGYRO
    | mavlink.HIGHRES_IMU_UPDATED_YGYRO
    | mavlink.HIGHRES_IMU_UPDATED_ZGYRO
)
_MAG_FIELDS = mavlink.HIGHRES_IMU_UPDATED_XMAG | mavlink.HIGHRES_IMU_UPDATED_YMAG | mavlink.HIGHRES_IMU_UPDATED_ZMAG
_BARO_FIELDS = (
    mavlink.HIGHRES_IMU_UPDATED_ABS_PRESSURE
    | mavlink.HIGHRES_IMU_UPDATED_PRESSURE_ALT
    | mavlink.HIGHRES_IMU_UPDATED_TEMPERATURE
)
UINT16_UNKNOWN = 65535


class Telemetry:
    """Builds the stream messages of one vehicle; remembers which sensor samples each stream has sent."""

    def __init__(self, vehicle: SimulatedPixhawk, unix_time_us: Callable[[], int] | None = None) -> None:
        self.vehicle = vehicle
        self._unix_time_us = unix_time_us or (lambda: time.time_ns() // 1000)
        self._sent: dict[tuple[int, type], int] = {}
        self._fresh_only = True
        self.builders: dict[int, Callable[[], Message | None]] = {
            mavlink.MAVLINK_MSG_ID_TIMESYNC: self.timesync,
            mavlink.MAVLINK_MSG_ID_HIGHRES_IMU: self.highres_imu,
            mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: self.local_position_ned,
            mavlink.MAVLINK_MSG_ID_ATTITUDE: self.attitude,
            mavlink.MAVLINK_MSG_ID_ODOMETRY: self.odometry,
            mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: self.attitude_quaternion,
            mavlink.MAVLINK_MSG_ID_ATTITUDE_TARGET: self.attitude_target,
            mavlink.MAVLINK_MSG_ID_BATTERY_STATUS: self.battery_status,
            mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: self.extended_sys_state,
            mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: self.global_position_int,
            mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: self.gps_global_origin,
            mavlink.MAVLINK_MSG_ID_GPS_RAW_INT: self.gps_raw_int,
            mavlink.MAVLINK_MSG_ID_HOME_POSITION: self.home_position,
            mavlink.MAVLINK_MSG_ID_SCALED_PRESSURE: self.scaled_pressure,
            mavlink.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: self.servo_output_raw,
            mavlink.MAVLINK_MSG_ID_SYS_STATUS: self.sys_status,
            mavlink.MAVLINK_MSG_ID_SYSTEM_TIME: self.system_time,
            mavlink.MAVLINK_MSG_ID_VFR_HUD: self.vfr_hud,
            mavlink.MAVLINK_MSG_ID_SIM_STATE: self.sim_state,
            mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION: self.autopilot_version,
        }

    def build(self, msg_id: int) -> Message | None:
        """The message now, or None when a sensor stream has no new sample (or the id is not built here)."""
        builder = self.builders.get(msg_id)
        return builder() if builder is not None else None

    def request(self, msg_id: int) -> Message | None:
        """The message for MAV_CMD_REQUEST_MESSAGE: a sensor message carries its latest sample, sent or not."""
        self._fresh_only = False
        try:
            return self.build(msg_id)
        finally:
            self._fresh_only = True

    def _new(self, msg_id: int, kind: type) -> bool:
        """Whether the vehicle has a sample of ``kind`` this stream has not sent yet (and mark it sent); on a
        request, whether it has one at all."""
        sample = self.vehicle.samples.get(kind)
        if sample is None:
            return False
        if not self._fresh_only:
            return True
        if self._sent.get((msg_id, kind)) == sample.sequence:
            return False
        self._sent[(msg_id, kind)] = sample.sequence
        return True

    # ------------------------------------------------------------------ sensors

    def highres_imu(self) -> Message | None:
        msg_id = mavlink.MAVLINK_MSG_ID_HIGHRES_IMU
        if not self._new(msg_id, ImuSample):
            return None
        samples = self.vehicle.samples
        imu = samples[ImuSample]
        fields = _IMU_FIELDS
        mag = samples.get(MagSample)
        baro = samples.get(BaroSample)
        if self._new(msg_id, MagSample):
            fields |= _MAG_FIELDS
        if self._new(msg_id, BaroSample):
            fields |= _BARO_FIELDS
        ax, ay, az = imu.value.accel
        gx, gy, gz = imu.value.gyro
        mx, my, mz = mag.value.field if mag is not None else (math.nan, math.nan, math.nan)
        pressure = baro.value.pressure_pa if baro is not None else math.nan
        temperature = baro.value.temperature if baro is not None else imu.value.temperature
        return mavlink.MAVLink_highres_imu_message(
            time_usec=imu.boot_us,
            xacc=ax,
            yacc=ay,
            zacc=az,
            xgyro=gx,
            ygyro=gy,
            zgyro=gz,
            xmag=mx,
            ymag=my,
            zmag=mz,
            abs_pressure=pressure / 100.0,
            diff_pressure=0.0,
            pressure_alt=isa_altitude_m(pressure) if baro is not None else math.nan,
            temperature=temperature,
            fields_updated=fields,
            id=0,
        )

    def scaled_pressure(self) -> Message | None:
        baro = self.vehicle.samples.get(BaroSample)
        if baro is None:
            return None
        value: BaroSample = baro.value
        return mavlink.MAVLink_scaled_pressure_message(
            time_boot_ms(baro.boot_us), value.pressure_pa / 100.0, 0.0, round(value.temperature * 100.0), 0
        )

    def gps_raw_int(self) -> Message | None:
        if not self._new(mavlink.MAVLINK_MSG_ID_GPS_RAW_INT, GpsSample):
            return None
        gps = self.vehicle.samples[GpsSample]
        s: GpsSample = gps.value
        vn, ve, _ = s.vel_ned
        fix = s.fix_type >= 3
        alt_mm = round(s.alt_msl * 1000.0) if fix else 0
        return mavlink.MAVLink_gps_raw_int_message(
            time_usec=gps.boot_us,
            fix_type=s.fix_type,
            lat=deg_e7(s.lat),
            lon=deg_e7(s.lon),
            alt=alt_mm,
            eph=round(s.hdop * 100.0),
            epv=round(s.vdop * 100.0),
            vel=round(math.hypot(vn, ve) * 100.0) if fix else UINT16_UNKNOWN,
            cog=round(math.degrees(math.atan2(ve, vn)) % 360.0 * 100.0) % 36000 if fix else UINT16_UNKNOWN,
            satellites_visible=s.satellites,
            alt_ellipsoid=alt_mm,
            h_acc=round(s.eph * 1000.0),
            v_acc=round(s.epv * 1000.0),
            vel_acc=round(s.s_variance_m_s * 1000.0),
            hdg_acc=0,
            yaw=0,
        )

    # ------------------------------------------------------------------ estimate (the truth)

    def attitude(self) -> Message:
        v = self.vehicle
        return attitude_message(v.time_us, v.truth.q, v.control.body_rates)

    def attitude_quaternion(self) -> Message:
        v = self.vehicle
        return attitude_quaternion_message(v.time_us, v.truth.q, v.control.body_rates)

    def local_position_ned(self) -> Message:
        v = self.vehicle
        return local_position_ned_message(v.time_us, v.truth.position, v.truth.velocity)

    def odometry(self) -> Message:
        """PX4's ODOMETRY: pose in LOCAL_NED, velocity and rates in BODY_FRD; covariances unknown (NaN first)."""
        v = self.vehicle
        t = v.truth
        unknown = (math.nan,) + (0.0,) * 20
        x, y, z = t.position
        vx, vy, vz = quat.rotate_inv(t.q, t.velocity)
        p, q, r = v.control.body_rates
        return mavlink.MAVLink_odometry_message(
            time_usec=v.time_us,
            frame_id=mavlink.MAV_FRAME_LOCAL_NED,
            child_frame_id=mavlink.MAV_FRAME_BODY_FRD,
            x=x,
            y=y,
            z=z,
            q=t.q,
            vx=vx,
            vy=vy,
            vz=vz,
            rollspeed=p,
            pitchspeed=q,
            yawspeed=r,
            pose_covariance=unknown,
            velocity_covariance=unknown,
            reset_counter=0,
            estimator_type=mavlink.MAV_ESTIMATOR_TYPE_UNKNOWN,
            quality=100,
        )

    def global_position_int(self) -> Message:
        v = self.vehicle
        t = v.truth
        vn, ve, vd = t.velocity
        return mavlink.MAVLink_global_position_int_message(
            time_boot_ms=time_boot_ms(v.time_us),
            lat=deg_e7(t.lat),
            lon=deg_e7(t.lon),
            alt=round(t.alt * 1000.0),
            relative_alt=round((t.alt - v.home.alt) * 1000.0),
            vx=round(vn * 100.0),
            vy=round(ve * 100.0),
            vz=round(vd * 100.0),
            hdg=cdeg(quat.yaw(t.q)),
        )

    def vfr_hud(self) -> Message:
        v = self.vehicle
        t = v.truth
        speed = math.hypot(t.velocity[0], t.velocity[1])
        throttle = round(min(max(-v.output.thrust_body[2], 0.0), 1.0) * 100.0)
        return mavlink.MAVLink_vfr_hud_message(
            airspeed=speed,
            groundspeed=speed,
            heading=cdeg(quat.yaw(t.q)) // 100,
            throttle=throttle,
            alt=t.alt,
            climb=-t.velocity[2],
        )

    def attitude_target(self) -> Message:
        """What the controllers fly: the attitude setpoint (when attitude is controlled) and the rate setpoint."""
        v = self.vehicle
        out = v.output
        q = out.q_sp
        mask = 0
        if q[0] != q[0]:
            q, mask = quat.IDENTITY, mavlink.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE
        rates = tuple(r if r == r else 0.0 for r in out.rates_sp)
        return mavlink.MAVLink_attitude_target_message(time_boot_ms(v.time_us), mask, q, *rates, -out.thrust_body[2])

    def sim_state(self) -> Message:
        """The truth (see the module docstring for where the NED position is)."""
        t = self.vehicle.truth
        roll, pitch, yaw = quat.to_euler(t.q)
        q1, q2, q3, q4 = t.q
        ax, ay, az = t.specific_force
        gx, gy, gz = t.angular_velocity
        vn, ve, vd = t.velocity
        return mavlink.MAVLink_sim_state_message(
            q1=q1,
            q2=q2,
            q3=q3,
            q4=q4,
            roll=roll,
            pitch=pitch,
            yaw=yaw,
            xacc=ax,
            yacc=ay,
            zacc=az,
            xgyro=gx,
            ygyro=gy,
            zgyro=gz,
            lat=t.lat,
            lon=t.lon,
            alt=t.alt,
            std_dev_horz=0.0,
            std_dev_vert=0.0,
            vn=vn,
            ve=ve,
            vd=vd,
            lat_int=deg_e7(t.lat),
            lon_int=deg_e7(t.lon),
        )

    # ------------------------------------------------------------------ system

    def timesync(self) -> Message:
        """A TIMESYNC request (tc1 = 0, ts1 = boot time in ns), PX4's 10 Hz ONBOARD stream."""
        return mavlink.MAVLink_timesync_message(0, self.vehicle.time_us * 1000)

    def sys_status(self) -> Message:
        v = self.vehicle
        battery = v.battery_state
        health = SENSORS
        if not v.commander.arming_denial(v.time_us, v.condition()):
            health |= mavlink.MAV_SYS_STATUS_PREARM_CHECK
        present = SENSORS | mavlink.MAV_SYS_STATUS_PREARM_CHECK
        return mavlink.MAVLink_sys_status_message(
            onboard_control_sensors_present=present,
            onboard_control_sensors_enabled=present,
            onboard_control_sensors_health=health,
            load=0,
            voltage_battery=round(battery.voltage_v * 1000.0),
            current_battery=battery_current_ca(battery.current_a),
            battery_remaining=battery_remaining_pct(battery.remaining),
            drop_rate_comm=0,
            errors_comm=0,
            errors_count1=0,
            errors_count2=0,
            errors_count3=0,
            errors_count4=0,
            onboard_control_sensors_present_extended=0,
            onboard_control_sensors_enabled_extended=0,
            onboard_control_sensors_health_extended=0,
        )

    def battery_status(self) -> Message:
        return battery_status_message(BatteryStatus(**self.vehicle.battery_state._asdict()))

    def extended_sys_state(self) -> Message:
        v = self.vehicle
        nav_state = px4_modes.to_nav_state(v.commander.mode)
        landed_state = landed_state_of(v.landed.landed, nav_state if nav_state is not None else -1)
        return extended_sys_state_message(landed_state)

    def home_position(self) -> Message:
        v = self.vehicle
        h = v.home
        return mavlink.MAVLink_home_position_message(
            latitude=deg_e7(h.lat),
            longitude=deg_e7(h.lon),
            altitude=round(h.alt * 1000.0),
            x=h.x,
            y=h.y,
            z=h.z,
            q=(1.0, 0.0, 0.0, 0.0),
            approach_x=0.0,
            approach_y=0.0,
            approach_z=0.0,
            time_usec=v.time_us,
        )

    def gps_global_origin(self) -> Message:
        """The NED origin: the simulator's home (SIH_LOC_LAT0, SIH_LOC_LON0, SIH_LOC_H0)."""
        v = self.vehicle
        lat, lon, alt = v.sim.home
        return mavlink.MAVLink_gps_global_origin_message(deg_e7(lat), deg_e7(lon), round(alt * 1000.0), v.time_us)

    def servo_output_raw(self) -> Message:
        v = self.vehicle
        pwm = [round(us) for us in v.output.pwm[:16]]
        pwm += [0] * (16 - len(pwm))
        return mavlink.MAVLink_servo_output_raw_message(v.time_us & 0xFFFFFFFF, 0, *pwm)

    def system_time(self) -> Message:
        return mavlink.MAVLink_system_time_message(self._unix_time_us(), time_boot_ms(self.vehicle.time_us))

    def autopilot_version(self) -> Message:
        major, minor, patch = PX4_VERSION_MODELLED
        version = (major << 24) | (minor << 16) | (patch << 8) | mavlink.FIRMWARE_VERSION_TYPE_OFFICIAL
        return mavlink.MAVLink_autopilot_version_message(
            CAPABILITIES, version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, 0, [0] * 18
        )
