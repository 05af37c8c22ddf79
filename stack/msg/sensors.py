"""Raw sensor messages (PX4 ``msg/Sensor*.msg``). Board frame = body FRD here; SI units."""

from __future__ import annotations

from stack.msg.base import NAN, Message


class SensorGyro(Message):
    """Angular rate from a gyroscope [rad/s], FRD."""

    timestamp_sample: int = 0
    device_id: int = 0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    temperature: float = NAN
    error_count: int = 0
    clip_counter: tuple[int, int, int] = (0, 0, 0)
    samples: int = 1


class SensorAccel(Message):
    """Specific force from an accelerometer [m/s²], FRD, gravity included (reads −g on z at rest)."""

    timestamp_sample: int = 0
    device_id: int = 0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    temperature: float = NAN
    error_count: int = 0
    clip_counter: tuple[int, int, int] = (0, 0, 0)
    samples: int = 1


class SensorMag(Message):
    """Magnetic field [Gauss], FRD."""

    timestamp_sample: int = 0
    device_id: int = 0
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    temperature: float = NAN
    error_count: int = 0
    is_external: bool = False


class SensorBaro(Message):
    """Static pressure [Pa] and temperature [°C]."""

    timestamp_sample: int = 0
    device_id: int = 0
    pressure: float = 0.0
    temperature: float = NAN
    error_count: int = 0


class SensorGps(Message):
    """GNSS receiver output (PX4 ``SensorGps``, also published as ``vehicle_gps_position``)."""

    # Without a fix (fix_type below 2) a receiver reports no position or velocity; MAVLink's GPS_RAW_INT has no
    # vertical velocity, and may lack speed, course and their accuracy.
    NAN_MEANS_UNKNOWN = frozenset(
        {
            "latitude_deg",
            "longitude_deg",
            "altitude_msl_m",
            "altitude_ellipsoid_m",
            "s_variance_m_s",
            "vel_m_s",
            "vel_n_m_s",
            "vel_e_m_s",
            "vel_d_m_s",
            "cog_rad",
        }
    )

    FIX_TYPE_NONE = 1
    FIX_TYPE_2D = 2
    FIX_TYPE_3D = 3

    timestamp_sample: int = 0
    device_id: int = 0
    latitude_deg: float = 0.0
    longitude_deg: float = 0.0
    altitude_msl_m: float = 0.0
    altitude_ellipsoid_m: float = 0.0
    s_variance_m_s: float = 0.0
    c_variance_rad: float = 0.0
    fix_type: int = 0
    eph: float = NAN
    epv: float = NAN
    hdop: float = NAN
    vdop: float = NAN
    noise_per_ms: int = 0
    automatic_gain_control: int = 0
    jamming_state: int = 0
    jamming_indicator: int = 0
    spoofing_state: int = 0
    vel_m_s: float = 0.0
    vel_n_m_s: float = 0.0
    vel_e_m_s: float = 0.0
    vel_d_m_s: float = 0.0
    cog_rad: float = 0.0
    vel_ned_valid: bool = False
    timestamp_time_relative: int = 0
    time_utc_usec: int = 0
    satellites_used: int = 0
    heading: float = NAN
    heading_offset: float = NAN
    heading_accuracy: float = NAN
