"""MAVLink messages ↔ the stack's uORB-style messages, I/O-free.

Inbound, each function takes a decoded pymavlink message (anything with the MAVLink field names) and the
time its data was sampled, already mapped onto the stack's clock (``TimeSync.to_local_us``), and returns
the stack's messages; a value that is NaN or outside what a sensor can report raises :class:`Refused`
with the reason, and the caller counts and drops it. Units follow the MAVLink common message set
(``message_definitions/v1.0/common.xml``) in and PX4's uORB definitions (``msg/*.msg``) out: HIGHRES_IMU
gives SI rates and accelerations, gauss and hPa (→ Pa); GPS_RAW_INT degE7, mm, cm/s and cdeg; SYS_STATUS
and BATTERY_STATUS mV, cA and %. Frames need no change: MAVLink's body frame is FRD and its local frame
NED, the stack's too, and MAVLink quaternions are Hamilton (w, x, y, z) rotating body to NED.

Outbound, :func:`rates_target` and :func:`attitude_target` turn the stack's ``vehicle_rates_setpoint`` /
``vehicle_attitude_setpoint`` into SET_ATTITUDE_TARGET fields (PX4 ``MavlinkReceiver::
handle_message_set_attitude_target``): collective thrust = −``thrust_body[2]`` in [0, 1]; a NaN or
out-of-range setpoint is refused, never sent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import common as mavlink2

from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.msg.base import Message
from stack.msg.estimation import VehicleAngularVelocity, VehicleAttitude, VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorBaro, SensorGps, SensorGyro, SensorMag
from stack.msg.setpoints import VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import BatteryStatus
from stack.msg.topic import Topic

# HIGHRES_IMU_UPDATED_FLAGS
GYRO_UPDATED = (
    mavlink2.HIGHRES_IMU_UPDATED_XGYRO | mavlink2.HIGHRES_IMU_UPDATED_YGYRO | mavlink2.HIGHRES_IMU_UPDATED_ZGYRO
)
ACCEL_UPDATED = (
    mavlink2.HIGHRES_IMU_UPDATED_XACC | mavlink2.HIGHRES_IMU_UPDATED_YACC | mavlink2.HIGHRES_IMU_UPDATED_ZACC
)
MAG_UPDATED = mavlink2.HIGHRES_IMU_UPDATED_XMAG | mavlink2.HIGHRES_IMU_UPDATED_YMAG | mavlink2.HIGHRES_IMU_UPDATED_ZMAG
BARO_UPDATED = mavlink2.HIGHRES_IMU_UPDATED_ABS_PRESSURE
TEMPERATURE_UPDATED = mavlink2.HIGHRES_IMU_UPDATED_TEMPERATURE

# What a sensor can physically report; beyond it a value is corrupt, not a measurement.
GYRO_MAX_RAD_S = 70.0  # 4000 °/s, twice the widest MEMS gyro range
ACCEL_MAX_M_S2 = 40.0 * CONSTANTS_ONE_G
MAG_MAX_GAUSS = 16.0
PRESSURE_RANGE_PA = (1_000.0, 120_000.0)
TEMPERATURE_RANGE_C = (-60.0, 150.0)
RATE_SETPOINT_MAX_RAD_S = 20.0
QUATERNION_NORM_TOLERANCE = 0.01
UNIX_TIME_MIN_US = 10**15
"""A ``time_usec`` above this (2001-09-09) is UNIX time, not time since boot (MAVLink allows either)."""

HPA_TO_PA = 100.0
UINT16_MAX = 0xFFFF
INT16_MAX = 0x7FFF
MAX_CELL_V = 5.0

BATTERY_WARNING = {
    mavlink2.MAV_BATTERY_CHARGE_STATE_LOW: BatteryStatus.WARNING_LOW,
    mavlink2.MAV_BATTERY_CHARGE_STATE_CRITICAL: BatteryStatus.WARNING_CRITICAL,
    mavlink2.MAV_BATTERY_CHARGE_STATE_EMERGENCY: BatteryStatus.WARNING_EMERGENCY,
    mavlink2.MAV_BATTERY_CHARGE_STATE_FAILED: BatteryStatus.WARNING_EMERGENCY,
    mavlink2.MAV_BATTERY_CHARGE_STATE_UNHEALTHY: BatteryStatus.WARNING_EMERGENCY,
}
"""MAV_BATTERY_CHARGE_STATE → ``battery_status.warning`` (PX4's BATTERY_STATUS stream maps it the other way)."""

RATES_TYPE_MASK = mavlink2.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE
ATTITUDE_TYPE_MASK = (
    mavlink2.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
    | mavlink2.ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE
    | mavlink2.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE
)


class Refused(ValueError):
    """A message (or part of one) that cannot be used, with the reason."""


def _finite(name: str, *values: float) -> None:
    if not all(math.isfinite(v) for v in values):
        raise Refused(f"{name}: not finite {values}")


def _within(name: str, limit: float, *values: float) -> None:
    _finite(name, *values)
    if any(abs(v) > limit for v in values):
        raise Refused(f"{name}: {values} beyond ±{limit:g}")


def is_unix_time(time_usec: int) -> bool:
    return time_usec >= UNIX_TIME_MIN_US


# -- inbound: sensors ----------------------------------------------------------------------------------


def highres_imu(msg: Any, sample_us: int, device_id: int) -> tuple[list[tuple[Topic, Message]], list[str]]:
    """HIGHRES_IMU → ``sensor_accel``, ``sensor_gyro``, ``sensor_mag``, ``sensor_baro``: only the sensors
    ``fields_updated`` marks as new, in the order the attitude estimator wants them (accelerometer before
    its trigger, the gyro). Returns the messages and the reasons any part was refused."""
    updated = msg.fields_updated
    out: list[tuple[Topic, Message]] = []
    refused: list[str] = []
    temperature = math.nan
    if updated & TEMPERATURE_UPDATED:
        lo, hi = TEMPERATURE_RANGE_C
        temperature = msg.temperature if lo <= msg.temperature <= hi else math.nan
    if updated & ACCEL_UPDATED == ACCEL_UPDATED:
        try:
            _within("HIGHRES_IMU acceleration", ACCEL_MAX_M_S2, msg.xacc, msg.yacc, msg.zacc)
            out.append(
                (
                    ORB_ID.sensor_accel,
                    SensorAccel(
                        timestamp_sample=sample_us,
                        device_id=device_id,
                        x=msg.xacc,
                        y=msg.yacc,
                        z=msg.zacc,
                        temperature=temperature,
                    ),
                )
            )
        except Refused as e:
            refused.append(str(e))
    if updated & GYRO_UPDATED == GYRO_UPDATED:
        try:
            _within("HIGHRES_IMU angular rate", GYRO_MAX_RAD_S, msg.xgyro, msg.ygyro, msg.zgyro)
            out.append(
                (
                    ORB_ID.sensor_gyro,
                    SensorGyro(
                        timestamp_sample=sample_us,
                        device_id=device_id,
                        x=msg.xgyro,
                        y=msg.ygyro,
                        z=msg.zgyro,
                        temperature=temperature,
                    ),
                )
            )
        except Refused as e:
            refused.append(str(e))
    if updated & MAG_UPDATED == MAG_UPDATED:
        try:
            _within("HIGHRES_IMU magnetic field", MAG_MAX_GAUSS, msg.xmag, msg.ymag, msg.zmag)
            out.append(
                (
                    ORB_ID.sensor_mag,
                    SensorMag(timestamp_sample=sample_us, device_id=device_id, x=msg.xmag, y=msg.ymag, z=msg.zmag),
                )
            )
        except Refused as e:
            refused.append(str(e))
    if updated & BARO_UPDATED:
        pressure = msg.abs_pressure * HPA_TO_PA
        lo, hi = PRESSURE_RANGE_PA
        if math.isfinite(pressure) and lo <= pressure <= hi:
            out.append(
                (
                    ORB_ID.sensor_baro,
                    SensorBaro(
                        timestamp_sample=sample_us, device_id=device_id, pressure=pressure, temperature=temperature
                    ),
                )
            )
        else:
            refused.append(f"HIGHRES_IMU abs_pressure: {msg.abs_pressure!r} hPa outside {lo / 100:g}–{hi / 100:g}")
    return out, refused


def gps_raw_int(msg: Any, sample_us: int, device_id: int) -> SensorGps:
    """GPS_RAW_INT → ``sensor_gps``. It has no vertical velocity, so the NED velocity is not marked valid
    (the horizontal one is filled in from ground speed and course); accuracies come from the MAVLink 2
    extensions h_acc/v_acc/vel_acc when given (0 = unknown), DOPs from eph/epv (UINT16_MAX = unknown)."""
    lat, lon = msg.lat * 1e-7, msg.lon * 1e-7
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
        raise Refused(f"GPS_RAW_INT: latitude/longitude {lat:g}/{lon:g} out of range")
    hdop = msg.eph / 100.0 if msg.eph != UINT16_MAX else math.nan
    vdop = msg.epv / 100.0 if msg.epv != UINT16_MAX else math.nan
    h_acc = getattr(msg, "h_acc", 0)
    v_acc = getattr(msg, "v_acc", 0)
    vel_acc = getattr(msg, "vel_acc", 0)
    alt_ellipsoid = getattr(msg, "alt_ellipsoid", 0)
    speed = msg.vel / 100.0 if msg.vel != UINT16_MAX else math.nan
    course = math.radians(msg.cog / 100.0) if msg.cog != UINT16_MAX else math.nan
    return SensorGps(
        timestamp_sample=sample_us,
        device_id=device_id,
        latitude_deg=lat,
        longitude_deg=lon,
        altitude_msl_m=msg.alt * 1e-3,
        altitude_ellipsoid_m=alt_ellipsoid * 1e-3 if alt_ellipsoid else msg.alt * 1e-3,
        s_variance_m_s=vel_acc * 1e-3 if vel_acc else math.nan,
        fix_type=msg.fix_type,
        eph=h_acc * 1e-3 if h_acc else hdop,
        epv=v_acc * 1e-3 if v_acc else vdop,
        hdop=hdop,
        vdop=vdop,
        vel_m_s=speed,
        vel_n_m_s=speed * math.cos(course),
        vel_e_m_s=speed * math.sin(course),
        vel_d_m_s=math.nan,
        cog_rad=course,
        vel_ned_valid=False,
        time_utc_usec=msg.time_usec if is_unix_time(msg.time_usec) else 0,
        satellites_used=msg.satellites_visible if msg.satellites_visible != 0xFF else 0,
    )


def battery_status(msg: Any) -> BatteryStatus:
    """BATTERY_STATUS → ``battery_status``: the pack voltage is the sum of the cells reported (UINT16_MAX marks
    an absent cell in ``voltages``, 0 in ``voltages_ext``); a pack reported as a whole in cell 0 has no cell count."""
    cells = [v for v in msg.voltages if v != UINT16_MAX] + [v for v in getattr(msg, "voltages_ext", ()) if v]
    voltage = sum(cells) * 1e-3
    remaining = msg.battery_remaining / 100.0 if 0 <= msg.battery_remaining <= 100 else -1.0
    current = msg.current_battery / 100.0 if msg.current_battery >= 0 else -1.0
    whole_pack = len(cells) == 1 and voltage > MAX_CELL_V
    return BatteryStatus(
        connected=voltage > 0.0 or remaining >= 0.0,
        voltage_v=voltage,
        current_a=current,
        current_average_a=current,
        discharged_mah=float(msg.current_consumed) if msg.current_consumed >= 0 else -1.0,
        remaining=remaining,
        time_remaining_s=float(msg.time_remaining) if getattr(msg, "time_remaining", 0) > 0 else math.nan,
        temperature=msg.temperature / 100.0 if msg.temperature != INT16_MAX else math.nan,
        cell_count=0 if whole_pack else len(cells),
        warning=BATTERY_WARNING.get(getattr(msg, "charge_state", 0), BatteryStatus.WARNING_NONE),
    )


def sys_status_battery(msg: Any) -> BatteryStatus:
    """SYS_STATUS's battery fields → ``battery_status``, for an autopilot that sends no BATTERY_STATUS."""
    voltage = msg.voltage_battery * 1e-3 if msg.voltage_battery != UINT16_MAX else 0.0
    remaining = msg.battery_remaining / 100.0 if 0 <= msg.battery_remaining <= 100 else -1.0
    current = msg.current_battery / 100.0 if msg.current_battery >= 0 else -1.0
    return BatteryStatus(
        connected=voltage > 0.0 or remaining >= 0.0,
        voltage_v=voltage,
        current_a=current,
        current_average_a=current,
        remaining=remaining,
    )


def prearm_ok(msg: Any) -> bool | None:
    """SYS_STATUS's MAV_SYS_STATUS_PREARM_CHECK health bit (what MAVSDK calls "armable"), None if not reported."""
    bit = mavlink2.MAV_SYS_STATUS_PREARM_CHECK
    if not msg.onboard_control_sensors_present & bit:
        return None
    return bool(msg.onboard_control_sensors_health & bit)


STATUSTEXT_CHUNK = 50
STATUSTEXT_PENDING = 4


class StatustextAssembler:
    """STATUSTEXT chunks → whole texts. A text longer than a message's 50 characters goes out in chunks that
    share a non-zero ``id``, numbered by ``chunk_seq``; a chunk shorter than 50 (NUL-terminated) ends it
    (``common.xml``, STATUSTEXT). Only the last few unfinished texts are kept."""

    def __init__(self) -> None:
        self._parts: dict[int, list[str]] = {}

    def add(self, text: str | bytes, text_id: int, chunk_seq: int) -> str | None:
        """The whole text once its last chunk is in, else None."""
        if isinstance(text, bytes):
            text = text.decode(errors="replace")
        text = text.split("\0", 1)[0]
        if text_id == 0:
            return text
        parts = self._parts.pop(text_id, [])
        if chunk_seq == 0:
            parts = []
        parts.append(text)
        if len(text) < STATUSTEXT_CHUNK:
            return "".join(parts)
        self._parts[text_id] = parts
        while len(self._parts) > STATUSTEXT_PENDING:
            del self._parts[next(iter(self._parts))]
        return None


# -- inbound: the autopilot's own estimate -------------------------------------------------------------


def _unit_quaternion(name: str, q: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    _finite(name, *q)
    if abs(quat.norm(q) - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise Refused(f"{name}: quaternion {q} is not a unit quaternion")
    return quat.normalized(q)


def attitude_quaternion(msg: Any, sample_us: int) -> tuple[VehicleAttitude, VehicleAngularVelocity]:
    """ATTITUDE_QUATERNION → ``vehicle_attitude`` and ``vehicle_angular_velocity`` (the autopilot's estimate)."""
    q = _unit_quaternion("ATTITUDE_QUATERNION", (msg.q1, msg.q2, msg.q3, msg.q4))
    _within("ATTITUDE_QUATERNION body rates", GYRO_MAX_RAD_S, msg.rollspeed, msg.pitchspeed, msg.yawspeed)
    return (
        VehicleAttitude(timestamp_sample=sample_us, q=q),
        VehicleAngularVelocity(timestamp_sample=sample_us, xyz=(msg.rollspeed, msg.pitchspeed, msg.yawspeed)),
    )


@dataclass(frozen=True, slots=True)
class LocalOrigin:
    """The autopilot's local-frame origin (GPS_GLOBAL_ORIGIN): degrees and metres AMSL; NaN when unknown."""

    lat: float = math.nan
    lon: float = math.nan
    alt: float = math.nan


def gps_global_origin(msg: Any) -> LocalOrigin:
    return LocalOrigin(msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3)


def local_position_ned(msg: Any, sample_us: int, origin: LocalOrigin) -> VehicleLocalPosition:
    """LOCAL_POSITION_NED → ``vehicle_local_position``. The message carries no accuracy, so ``eph``/``epv``
    are NaN (not reported) rather than PX4's "unknown" infinity, which would fail every position check."""
    _finite("LOCAL_POSITION_NED", msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz)
    return _local_position(sample_us, (msg.x, msg.y, msg.z), (msg.vx, msg.vy, msg.vz), origin, math.nan, math.nan)


def _local_position(
    sample_us: int,
    position: tuple[float, float, float],
    velocity: tuple[float, float, float],
    origin: LocalOrigin,
    eph: float,
    epv: float,
    heading: float = math.nan,
) -> VehicleLocalPosition:
    referenced = math.isfinite(origin.lat) and math.isfinite(origin.lon)
    return VehicleLocalPosition(
        timestamp_sample=sample_us,
        xy_valid=True,
        z_valid=True,
        v_xy_valid=True,
        v_z_valid=True,
        x=position[0],
        y=position[1],
        z=position[2],
        vx=velocity[0],
        vy=velocity[1],
        vz=velocity[2],
        z_deriv=velocity[2],
        heading=heading if math.isfinite(heading) else 0.0,
        heading_good_for_control=math.isfinite(heading),
        xy_global=referenced,
        z_global=math.isfinite(origin.alt),
        ref_lat=origin.lat,
        ref_lon=origin.lon,
        ref_alt=origin.alt,
        eph=eph,
        epv=epv,
        evh=math.nan,
        evv=math.nan,
    )


# ODOMETRY's covariances are the upper-right triangles of 6×6 matrices, row-major: the diagonal's indices.
_COVARIANCE_DIAGONAL = (0, 6, 11, 15, 18, 20)


def odometry(msg: Any, sample_us: int, origin: LocalOrigin) -> tuple[VehicleAttitude, VehicleLocalPosition]:
    """ODOMETRY (frame MAV_FRAME_LOCAL_NED, velocity in MAV_FRAME_BODY_FRD, as PX4 sends it) →
    ``vehicle_attitude`` and ``vehicle_local_position``, with eph/epv from the pose covariance when given."""
    if msg.frame_id != mavlink2.MAV_FRAME_LOCAL_NED:
        raise Refused(f"ODOMETRY: frame_id {msg.frame_id} is not MAV_FRAME_LOCAL_NED")
    q = _unit_quaternion("ODOMETRY", tuple(msg.q))
    _finite("ODOMETRY", msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz)
    velocity = (msg.vx, msg.vy, msg.vz)
    if msg.child_frame_id == mavlink2.MAV_FRAME_BODY_FRD:
        velocity = quat.rotate(q, velocity)
    elif msg.child_frame_id != mavlink2.MAV_FRAME_LOCAL_NED:
        raise Refused(f"ODOMETRY: child_frame_id {msg.child_frame_id} is neither BODY_FRD nor LOCAL_NED")
    var = [msg.pose_covariance[i] for i in _COVARIANCE_DIAGONAL[:3]]
    eph = math.sqrt(max(var[0], var[1])) if all(math.isfinite(v) and v >= 0 for v in var[:2]) else math.nan
    epv = math.sqrt(var[2]) if math.isfinite(var[2]) and var[2] >= 0 else math.nan
    lpos = _local_position(sample_us, (msg.x, msg.y, msg.z), velocity, origin, eph, epv, quat.yaw(q))
    return VehicleAttitude(timestamp_sample=sample_us, q=q), lpos


# -- inbound: the simulator's truth ----------------------------------------------------------------------


class TruthFrame:
    """SIM_STATE → ``sim_groundtruth``, in NED about the first position received (a simulated Pixhawk starts
    on the ground, as SIH does): SIM_STATE carries geodetic coordinates, no time and no ground contact.

    Positions use the degE7 MAVLink 2 extensions (1 cm) when present; the float degrees (about 0.5 m at
    mid latitudes) otherwise. The acceleration is SIM_STATE's body-frame specific force rotated to NED, plus
    gravity. ``on_ground``: within ``ground_tolerance_m`` of the starting height and nearly still.
    """

    def __init__(self, ground_tolerance_m: float = 0.1, still_m_s: float = 0.3) -> None:
        self.ground_tolerance_m = ground_tolerance_m
        self.still_m_s = still_m_s
        self.projection: MapProjection | None = None
        self.alt0 = 0.0

    def convert(self, msg: Any, sample_us: int) -> SimGroundtruth:
        lat, lon = (msg.lat_int * 1e-7, msg.lon_int * 1e-7) if msg.lat_int or msg.lon_int else (msg.lat, msg.lon)
        q = _unit_quaternion("SIM_STATE", (msg.q1, msg.q2, msg.q3, msg.q4))
        _finite("SIM_STATE", lat, lon, msg.alt, msg.vn, msg.ve, msg.vd, msg.xacc, msg.yacc, msg.zacc)
        _finite("SIM_STATE body rates", msg.xgyro, msg.ygyro, msg.zgyro)
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise Refused(f"SIM_STATE: latitude/longitude {lat:g}/{lon:g} out of range")
        if self.projection is None:
            self.projection = MapProjection(lat, lon)
            self.alt0 = msg.alt
        north, east = self.projection.project(lat, lon)
        down = self.alt0 - msg.alt
        velocity = (msg.vn, msg.ve, msg.vd)
        ax, ay, az = quat.rotate(q, (msg.xacc, msg.yacc, msg.zacc))
        on_ground = down > -self.ground_tolerance_m and math.hypot(*velocity) < self.still_m_s
        return SimGroundtruth(
            timestamp_sample=sample_us,
            position=(north, east, down),
            velocity=velocity,
            acceleration=(ax, ay, az + CONSTANTS_ONE_G),
            q=q,
            angular_velocity=(msg.xgyro, msg.ygyro, msg.zgyro),
            lat=lat,
            lon=lon,
            alt=msg.alt,
            on_ground=on_ground,
        )


# -- outbound ------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class AttitudeTarget:
    """The fields of one SET_ATTITUDE_TARGET (besides time and target ids)."""

    type_mask: int
    q: tuple[float, float, float, float]
    body_roll_rate: float
    body_pitch_rate: float
    body_yaw_rate: float
    thrust: float


def collective_thrust(thrust_body: tuple[float, float, float]) -> float:
    """SET_ATTITUDE_TARGET ``thrust`` [0, 1] from the stack's normalised body thrust (multicopter: −z)."""
    thrust = -thrust_body[2]
    if not math.isfinite(thrust):
        raise Refused(f"thrust {thrust_body} is not finite")
    if not -1e-6 <= thrust <= 1.0 + 1e-6:
        raise Refused(f"collective thrust {thrust:g} outside [0, 1]")
    return min(max(thrust, 0.0), 1.0)


def rates_target(sp: VehicleRatesSetpoint) -> AttitudeTarget:
    """``vehicle_rates_setpoint`` → body rates and thrust, attitude ignored. NaN (PX4: "hold this rate") is
    refused: a setpoint the Pixhawk would read differently is never sent."""
    _within("rates setpoint", RATE_SETPOINT_MAX_RAD_S, sp.roll, sp.pitch, sp.yaw)
    return AttitudeTarget(RATES_TYPE_MASK, quat.IDENTITY, sp.roll, sp.pitch, sp.yaw, collective_thrust(sp.thrust_body))


def attitude_target(sp: VehicleAttitudeSetpoint) -> AttitudeTarget:
    """``vehicle_attitude_setpoint`` → attitude (body → NED) and thrust, body rates ignored."""
    q = _unit_quaternion("attitude setpoint", sp.q_d)
    return AttitudeTarget(ATTITUDE_TYPE_MASK, q, 0.0, 0.0, 0.0, collective_thrust(sp.thrust_body))


IDLE_TARGET = AttitudeTarget(RATES_TYPE_MASK, quat.IDENTITY, 0.0, 0.0, 0.0, 0.0)
"""The proof-of-life setpoint while the stack is disarmed: no rotation, no thrust."""
