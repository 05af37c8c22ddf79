"""The telemetry a ground station sees, built from the stack's topics (I/O-free).

:class:`VehicleView` holds the latest message of each topic the streams read; each builder returns the MAVLink
message for it, or None when its data is not there (no position estimate yet: no GLOBAL_POSITION_INT), as PX4's
streams send nothing without data. Units are MAVLink's (``common.xml``): degE7, mm, cm/s, cdeg, mV, cA, %.

Where the stack's data differs from PX4's: the attitude comes from the estimator's 10 Hz ``estimator_status`` and
the body rates from the IMU's 10 Hz means (``vehicle_imu_status``) rather than the 250 Hz topics, so ATTITUDE
carries at most 10 new values per second of the stack's time; VFR_HUD has no airspeed sensor and no throttle
(both 0); SYS_STATUS reports no CPU load.

SYS_STATUS's sensor bits follow PX4's health reporting: a sensor is present once it has published, healthy
while it publishes (within the commander's SENSOR_TIMEOUT_US); the control bits are enabled as
``vehicle_control_mode`` says; PREARM_CHECK is healthy when the commander's pre-arm checks pass
(``vehicle_status.pre_flight_checks_pass``), which is what MAVSDK's ``is_armable`` reads.

The encodings the simulated Pixhawk shares (it builds from the simulator's truth rather than from topics):
:func:`time_boot_ms`, :func:`deg_e7`, :func:`cdeg`, and the ATTITUDE, ATTITUDE_QUATERNION, LOCAL_POSITION_NED and
EXTENDED_SYS_STATE messages from their values (:func:`attitude_message`, :func:`attitude_quaternion_message`,
:func:`local_position_ned_message`, :func:`extended_sys_state_message` with :func:`landed_state_of`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from stack.commander.health import SENSOR_TIMEOUT_US
from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.msg.estimation import EstimatorStatus, VehicleImuStatus, VehicleLocalPosition
from stack.msg.sensors import SensorBaro, SensorGps, SensorMag
from stack.msg.system import (
    BatteryStatus,
    HomePosition,
    VehicleControlMode,
    VehicleLandDetected,
    VehicleStatus,
)

NS = VehicleStatus
UINT16_MAX = 0xFFFF
INT16_MAX = 0x7FFF
INT32_MAX = 0x7FFF_FFFF
S = mavlink2  # MAV_SYS_STATUS_* bits

SENSOR_BITS = (
    S.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | S.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | S.MAV_SYS_STATUS_SENSOR_3D_MAG
    | S.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | S.MAV_SYS_STATUS_SENSOR_GPS
)
CONTROL_BITS = (
    S.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | S.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    | S.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | S.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    | S.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | S.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
)
ALWAYS_PRESENT = CONTROL_BITS | S.MAV_SYS_STATUS_AHRS | S.MAV_SYS_STATUS_PREARM_CHECK
CHARGE_STATE = {
    BatteryStatus.WARNING_NONE: S.MAV_BATTERY_CHARGE_STATE_OK,
    BatteryStatus.WARNING_LOW: S.MAV_BATTERY_CHARGE_STATE_LOW,
    BatteryStatus.WARNING_CRITICAL: S.MAV_BATTERY_CHARGE_STATE_CRITICAL,
    BatteryStatus.WARNING_EMERGENCY: S.MAV_BATTERY_CHARGE_STATE_EMERGENCY,
}


@dataclass
class VehicleView:
    """The latest message of each topic the telemetry reads (None until one arrives)."""

    status: VehicleStatus | None = None
    control_mode: VehicleControlMode | None = None
    land: VehicleLandDetected | None = None
    home: HomePosition | None = None
    local_position: VehicleLocalPosition | None = None
    estimator: EstimatorStatus | None = None
    imu: VehicleImuStatus | None = None
    gps: SensorGps | None = None
    battery: BatteryStatus | None = None
    mag: SensorMag | None = None
    baro: SensorBaro | None = None

    def clear_telemetry(self) -> None:
        """Forget what only a peer's telemetry reads (the topics read while a peer uses the link); keep what the
        HEARTBEAT, the acknowledgements and the missions need."""
        for field in TELEMETRY_FIELDS:
            setattr(self, field, None)


TELEMETRY_FIELDS = ("local_position", "estimator", "imu", "gps", "battery", "mag", "baro")
"""The fields of :class:`VehicleView` filled only while a peer uses the link."""


def _clamp_int(value: float, low: int, high: int) -> int:
    if not math.isfinite(value):
        return 0
    return max(low, min(high, round(value)))


def _fresh(now_us: int, stamp_us: int) -> bool:
    return stamp_us > 0 and now_us - stamp_us < SENSOR_TIMEOUT_US


def deg_e7(deg: float) -> int:
    """Degrees as MAVLink's degE7 integer (0 when unknown)."""
    return _clamp_int(deg * 1e7, -INT32_MAX, INT32_MAX)


def cdeg(angle_rad: float) -> int:
    """An angle as centidegrees in [0, 36000), UINT16_MAX when unknown."""
    if not math.isfinite(angle_rad):
        return UINT16_MAX
    return round(math.degrees(angle_rad) % 360.0 * 100.0) % 36000


def time_boot_ms(now_us: int) -> int:
    return (now_us // 1000) & 0xFFFF_FFFF


# -- attitude -------------------------------------------------------------------------------------


def _rates(view: VehicleView) -> tuple[float, float, float]:
    imu, est = view.imu, view.estimator
    if imu is None:
        return (0.0, 0.0, 0.0)
    bias = est.gyro_bias if est is not None else (0.0, 0.0, 0.0)
    return tuple(g - b for g, b in zip(imu.mean_gyro, bias, strict=True))  # type: ignore[return-value]


def _attitude_q(view: VehicleView, now_us: int) -> tuple[float, float, float, float] | None:
    est = view.estimator
    if est is None or not est.attitude_valid or not _fresh(now_us, est.attitude_timestamp):
        return None
    return est.q


def attitude_message(
    now_us: int, q: tuple[float, float, float, float], rates: tuple[float, float, float]
) -> mavlink2.MAVLink_attitude_message:
    """ATTITUDE: the attitude (w, x, y, z, body FRD → NED) as Euler angles, and the body rates [rad/s]."""
    roll, pitch, yaw = quat.to_euler(q)
    return mavlink2.MAVLink_attitude_message(time_boot_ms(now_us), roll, pitch, yaw, *rates)


def attitude_quaternion_message(
    now_us: int, q: tuple[float, float, float, float], rates: tuple[float, float, float]
) -> mavlink2.MAVLink_attitude_quaternion_message:
    """ATTITUDE_QUATERNION: the attitude and the body rates; no representation offset."""
    return mavlink2.MAVLink_attitude_quaternion_message(time_boot_ms(now_us), *q, *rates, [0.0, 0.0, 0.0, 0.0])


def attitude(view: VehicleView, now_us: int) -> mavlink2.MAVLink_attitude_message | None:
    q = _attitude_q(view, now_us)
    return attitude_message(now_us, q, _rates(view)) if q is not None else None


def attitude_quaternion(view: VehicleView, now_us: int) -> mavlink2.MAVLink_attitude_quaternion_message | None:
    q = _attitude_q(view, now_us)
    return attitude_quaternion_message(now_us, q, _rates(view)) if q is not None else None


# -- position -------------------------------------------------------------------------------------


def _global(lpos: VehicleLocalPosition) -> tuple[float, float, float] | None:
    """Latitude, longitude [deg] and altitude AMSL [m] of the local position, if it has a global reference."""
    if not (lpos.xy_valid and lpos.z_valid):
        return None
    if not all(math.isfinite(v) for v in (lpos.ref_lat, lpos.ref_lon, lpos.ref_alt)):
        return None
    lat, lon = MapProjection(lpos.ref_lat, lpos.ref_lon).reproject(lpos.x, lpos.y)
    return lat, lon, lpos.ref_alt - lpos.z


def _fresh_position(view: VehicleView, now_us: int) -> VehicleLocalPosition | None:
    lpos = view.local_position
    return lpos if lpos is not None and _fresh(now_us, lpos.timestamp) else None


def global_position_int(view: VehicleView, now_us: int) -> mavlink2.MAVLink_global_position_int_message | None:
    lpos = _fresh_position(view, now_us)
    where = _global(lpos) if lpos is not None else None
    if lpos is None or where is None:
        return None
    lat, lon, alt = where
    home_z = view.home.z if view.home is not None and view.home.valid_lpos else 0.0
    return mavlink2.MAVLink_global_position_int_message(
        time_boot_ms(now_us),
        deg_e7(lat),
        deg_e7(lon),
        _clamp_int(alt * 1000.0, -INT32_MAX, INT32_MAX),
        _clamp_int((home_z - lpos.z) * 1000.0, -INT32_MAX, INT32_MAX),
        _clamp_int(lpos.vx * 100.0, -INT16_MAX, INT16_MAX),
        _clamp_int(lpos.vy * 100.0, -INT16_MAX, INT16_MAX),
        _clamp_int(lpos.vz * 100.0, -INT16_MAX, INT16_MAX),
        cdeg(lpos.heading),
    )


def local_position_ned_message(
    now_us: int, position: tuple[float, float, float], velocity: tuple[float, float, float]
) -> mavlink2.MAVLink_local_position_ned_message:
    """LOCAL_POSITION_NED: position [m] and velocity [m/s] in the local NED frame."""
    return mavlink2.MAVLink_local_position_ned_message(time_boot_ms(now_us), *position, *velocity)


def local_position_ned(view: VehicleView, now_us: int) -> mavlink2.MAVLink_local_position_ned_message | None:
    lpos = _fresh_position(view, now_us)
    if lpos is None or not (lpos.xy_valid or lpos.z_valid):
        return None
    return local_position_ned_message(now_us, (lpos.x, lpos.y, lpos.z), (lpos.vx, lpos.vy, lpos.vz))


def gps_raw_int(view: VehicleView, now_us: int) -> mavlink2.MAVLink_gps_raw_int_message | None:
    gps = view.gps
    if gps is None:
        return None

    def dop(value: float) -> int:
        return _clamp_int(value * 100.0, 0, UINT16_MAX - 1) if math.isfinite(value) else UINT16_MAX

    def mm(value: float) -> int:
        return _clamp_int(value * 1000.0, 0, 0xFFFF_FFFF) if math.isfinite(value) else 0

    return mavlink2.MAVLink_gps_raw_int_message(
        gps.timestamp,
        gps.fix_type,
        deg_e7(gps.latitude_deg),
        deg_e7(gps.longitude_deg),
        _clamp_int(gps.altitude_msl_m * 1000.0, -INT32_MAX, INT32_MAX),
        dop(gps.hdop),
        dop(gps.vdop),
        _clamp_int(gps.vel_m_s * 100.0, 0, UINT16_MAX - 1),
        cdeg(gps.cog_rad) if gps.vel_ned_valid else UINT16_MAX,
        min(gps.satellites_used, 254),
        _clamp_int(gps.altitude_ellipsoid_m * 1000.0, -INT32_MAX, INT32_MAX),
        mm(gps.eph),
        mm(gps.epv),
        mm(math.sqrt(gps.s_variance_m_s)) if gps.s_variance_m_s >= 0.0 else 0,
        0,
        0,
    )


def home_position(view: VehicleView, now_us: int) -> mavlink2.MAVLink_home_position_message | None:
    home = view.home
    if home is None or not home.valid_hpos:
        return None
    return mavlink2.MAVLink_home_position_message(
        deg_e7(home.lat),
        deg_e7(home.lon),
        _clamp_int(home.alt * 1000.0, -INT32_MAX, INT32_MAX),
        home.x,
        home.y,
        home.z,
        list(quat.from_euler(0.0, 0.0, home.yaw if math.isfinite(home.yaw) else 0.0)),
        0.0,
        0.0,
        0.0,
        home.timestamp,
    )


def landed_state(view: VehicleView) -> int:
    """MAV_LANDED_STATE: on the ground when the land detector says landed; taking off or landing by the mode."""
    land, status = view.land, view.status
    if land is None:
        return mavlink2.MAV_LANDED_STATE_UNDEFINED
    return landed_state_of(land.landed, status.nav_state if status is not None else -1)


def landed_state_of(landed: bool, nav_state: int) -> int:
    """MAV_LANDED_STATE of a vehicle landed or not, in ``nav_state`` (PX4 ``streams/EXTENDED_SYS_STATE.hpp``)."""
    if landed:
        return mavlink2.MAV_LANDED_STATE_ON_GROUND
    if nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
        return mavlink2.MAV_LANDED_STATE_TAKEOFF
    if nav_state in (NS.NAVIGATION_STATE_AUTO_LAND, NS.NAVIGATION_STATE_DESCEND):
        return mavlink2.MAV_LANDED_STATE_LANDING
    return mavlink2.MAV_LANDED_STATE_IN_AIR


def extended_sys_state(view: VehicleView, now_us: int) -> mavlink2.MAVLink_extended_sys_state_message | None:
    if view.land is None:
        return None
    return extended_sys_state_message(landed_state(view))


def extended_sys_state_message(landed_state: int) -> mavlink2.MAVLink_extended_sys_state_message:
    """EXTENDED_SYS_STATE of a multicopter (no VTOL state)."""
    return mavlink2.MAVLink_extended_sys_state_message(mavlink2.MAV_VTOL_STATE_UNDEFINED, landed_state)


def vfr_hud(view: VehicleView, now_us: int) -> mavlink2.MAVLink_vfr_hud_message | None:
    lpos = _fresh_position(view, now_us)
    where = _global(lpos) if lpos is not None else None
    if lpos is None:
        return None
    heading = round(math.degrees(lpos.heading)) % 360 if math.isfinite(lpos.heading) else 0
    altitude = where[2] if where is not None else -lpos.z
    return mavlink2.MAVLink_vfr_hud_message(0.0, math.hypot(lpos.vx, lpos.vy), heading, 0, altitude, -lpos.vz)


# -- battery and health ---------------------------------------------------------------------------


def battery_status(view: VehicleView, now_us: int) -> mavlink2.MAVLink_battery_status_message | None:
    bat = view.battery
    if bat is None or not bat.connected:
        return None
    return battery_status_message(bat)


def battery_current_ca(current_a: float) -> int:
    """A pack's current in MAVLink's cA, -1 when no sensor measures it (a negative current_a)."""
    return _clamp_int(current_a * 100.0, -1, INT16_MAX) if current_a >= 0.0 else -1


def battery_remaining_pct(remaining: float) -> int:
    """A pack's remaining charge in MAVLink's %, -1 when unknown (a negative remaining)."""
    return _clamp_int(math.ceil(remaining * 100.0), 0, 100) if remaining >= 0.0 else -1


def battery_status_message(bat: BatteryStatus) -> mavlink2.MAVLink_battery_status_message:
    """BATTERY_STATUS of a connected pack."""
    cells = [UINT16_MAX] * 10
    if 0 < bat.cell_count <= 10:
        cells[: bat.cell_count] = [_clamp_int(bat.voltage_v / bat.cell_count * 1000.0, 0, UINT16_MAX - 1)] * (
            bat.cell_count
        )
    else:
        cells[0] = _clamp_int(bat.voltage_v * 1000.0, 0, UINT16_MAX - 1)
    temperature = (
        _clamp_int(bat.temperature * 100.0, -INT16_MAX, INT16_MAX - 1) if math.isfinite(bat.temperature) else INT16_MAX
    )
    return mavlink2.MAVLink_battery_status_message(
        0,
        mavlink2.MAV_BATTERY_FUNCTION_ALL,
        mavlink2.MAV_BATTERY_TYPE_LIPO,
        temperature,
        cells,
        battery_current_ca(bat.current_a),
        _clamp_int(bat.discharged_mah, -1, INT32_MAX) if bat.discharged_mah >= 0.0 else -1,
        -1,
        battery_remaining_pct(bat.remaining),
        _clamp_int(bat.time_remaining_s, 0, INT32_MAX) if math.isfinite(bat.time_remaining_s) else 0,
        CHARGE_STATE.get(bat.warning, mavlink2.MAV_BATTERY_CHARGE_STATE_UNDEFINED),
        [0, 0, 0, 0],
        0,
        0,
    )


def sensor_bits(view: VehicleView, now_us: int) -> tuple[int, int, int]:
    """SYS_STATUS onboard_control_sensors (present, enabled, health)."""
    present = ALWAYS_PRESENT
    health = 0
    imu = view.imu
    if imu is not None:
        present |= S.MAV_SYS_STATUS_SENSOR_3D_GYRO | S.MAV_SYS_STATUS_SENSOR_3D_ACCEL
        if _fresh(now_us, imu.timestamp):
            health |= S.MAV_SYS_STATUS_SENSOR_3D_GYRO if imu.gyro_rate_hz > 0.0 else 0
            health |= S.MAV_SYS_STATUS_SENSOR_3D_ACCEL if imu.accel_rate_hz > 0.0 else 0
    for msg, bit in (
        (view.mag, S.MAV_SYS_STATUS_SENSOR_3D_MAG),
        (view.baro, S.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE),
    ):
        if msg is not None:
            present |= bit
            health |= bit if _fresh(now_us, msg.timestamp) else 0
    gps = view.gps
    if gps is not None:
        present |= S.MAV_SYS_STATUS_SENSOR_GPS
        if _fresh(now_us, gps.timestamp) and gps.fix_type >= SensorGps.FIX_TYPE_3D:
            health |= S.MAV_SYS_STATUS_SENSOR_GPS
    if view.battery is not None and view.battery.connected:
        present |= S.MAV_SYS_STATUS_SENSOR_BATTERY
        health |= S.MAV_SYS_STATUS_SENSOR_BATTERY if view.battery.warning < BatteryStatus.WARNING_CRITICAL else 0
    if _attitude_q(view, now_us) is not None:
        health |= S.MAV_SYS_STATUS_AHRS
    enabled = (present & ~CONTROL_BITS) | _control_bits(view.control_mode)
    health |= CONTROL_BITS
    status = view.status
    if status is not None and status.pre_flight_checks_pass:
        health |= S.MAV_SYS_STATUS_PREARM_CHECK
    return present, enabled, health & present


def _control_bits(mode: VehicleControlMode | None) -> int:
    if mode is None:
        return 0
    bits = 0
    if mode.flag_control_rates_enabled:
        bits |= S.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    if mode.flag_control_attitude_enabled:
        bits |= S.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION | S.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    if mode.flag_control_altitude_enabled or mode.flag_control_climb_rate_enabled:
        bits |= S.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    if mode.flag_control_position_enabled or mode.flag_control_velocity_enabled:
        bits |= S.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    if mode.flag_armed:
        bits |= S.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    return bits


def sys_status(
    view: VehicleView, now_us: int, drop_rate_comm: float = 0.0, errors_comm: int = 0
) -> mavlink2.MAVLink_sys_status_message:
    """SYS_STATUS; ``drop_rate_comm`` the link's packet loss (0..1), ``errors_comm`` its framing errors."""
    present, enabled, health = sensor_bits(view, now_us)
    bat = view.battery
    connected = bat is not None and bat.connected
    return mavlink2.MAVLink_sys_status_message(
        present,
        enabled,
        health,
        0,
        _clamp_int(bat.voltage_v * 1000.0, 0, UINT16_MAX - 1) if connected else UINT16_MAX,
        battery_current_ca(bat.current_a) if connected else -1,
        battery_remaining_pct(bat.remaining) if connected else -1,
        _clamp_int(drop_rate_comm * 10000.0, 0, 10000),
        min(errors_comm, UINT16_MAX),
        0,
        0,
        0,
        0,
        0,
        0,
        0,
    )
