"""Estimator outputs (PX4 ``VehicleAngularVelocity``, ``VehicleAttitude``, ``VehicleLocalPosition``...)."""

from __future__ import annotations

import math

from stack.msg.base import F2, F3, F4, NAN, Q_IDENTITY, ZERO3, Message

INF = math.inf


class VehicleAngularVelocity(Message):
    """Bias-corrected, filtered body rates [rad/s] and their derivative [rad/s²] (the rate loop's input)."""

    timestamp_sample: int = 0
    xyz: F3 = ZERO3
    xyz_derivative: F3 = ZERO3


class VehicleAttitude(Message):
    """Attitude quaternion rotating body FRD to world NED."""

    timestamp_sample: int = 0
    q: F4 = Q_IDENTITY
    delta_q_reset: F4 = Q_IDENTITY
    quat_reset_counter: int = 0


class VehicleLocalPosition(Message):
    """Local position and velocity in NED about the reference point ``ref_lat``/``ref_lon``/``ref_alt``."""

    # Accuracies a source does not report (MAVLink's LOCAL_POSITION_NED carries none): NaN, as well as PX4's
    # infinite "unknown".
    NAN_MEANS_UNKNOWN = frozenset({"eph", "epv", "evh", "evv"})

    timestamp_sample: int = 0
    xy_valid: bool = False
    z_valid: bool = False
    v_xy_valid: bool = False
    v_z_valid: bool = False
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    delta_xy: F2 = (0.0, 0.0)
    xy_reset_counter: int = 0
    delta_z: float = 0.0
    z_reset_counter: int = 0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    z_deriv: float = 0.0
    delta_vxy: F2 = (0.0, 0.0)
    vxy_reset_counter: int = 0
    delta_vz: float = 0.0
    vz_reset_counter: int = 0
    ax: float = 0.0
    ay: float = 0.0
    az: float = 0.0
    heading: float = 0.0
    heading_var: float = 0.0
    unaided_heading: float = NAN
    delta_heading: float = 0.0
    heading_reset_counter: int = 0
    heading_good_for_control: bool = False
    tilt_var: float = 0.0
    xy_global: bool = False
    z_global: bool = False
    ref_timestamp: int = 0
    ref_lat: float = NAN
    ref_lon: float = NAN
    ref_alt: float = NAN
    dist_bottom_valid: bool = False
    dist_bottom: float = 0.0
    dist_bottom_var: float = 0.0
    eph: float = INF
    epv: float = INF
    evh: float = INF
    evv: float = INF
    dead_reckoning: bool = False
    vxy_max: float = INF
    vz_max: float = INF
    hagl_min: float = INF
    hagl_max_z: float = INF
    hagl_max_xy: float = INF


class VehicleGlobalPosition(Message):
    """Fused global position (WGS-84 latitude/longitude in degrees, altitude AMSL in metres)."""

    timestamp_sample: int = 0
    lat: float = NAN
    lon: float = NAN
    alt: float = NAN
    alt_ellipsoid: float = NAN
    lat_lon_valid: bool = False
    alt_valid: bool = False
    delta_alt: float = 0.0
    delta_terrain: float = 0.0
    lat_lon_reset_counter: int = 0
    alt_reset_counter: int = 0
    terrain_alt: float = NAN
    terrain_alt_valid: bool = False
    eph: float = INF
    epv: float = INF
    dead_reckoning: bool = False


class VehicleImuStatus(Message):
    """IMU health at a low rate (the subset of PX4 ``VehicleImuStatus`` a commander uses), ~10 Hz.

    The means are over the interval since the previous status, so a 10 Hz consumer sees what a
    250 Hz stream would tell it about motion (rotation, free fall) without receiving every sample.
    """

    timestamp_sample: int = 0
    accel_device_id: int = 0
    gyro_device_id: int = 0
    accel_error_count: int = 0
    gyro_error_count: int = 0
    accel_rate_hz: float = 0.0
    gyro_rate_hz: float = 0.0
    mean_accel: F3 = ZERO3
    mean_gyro: F3 = ZERO3
    max_gyro_norm: float = 0.0
    min_accel_norm: float = 0.0
    temperature_accel: float = NAN
    temperature_gyro: float = NAN


class EstimatorStatus(Message):
    """The attitude estimator's state at a low rate (~10 Hz) for the commander's checks.

    PX4's commander reads ``vehicle_attitude`` in-process for free; across processes a 10 Hz summary
    (the last attitude, when it and the body rates were published, the gyro bias) costs far less
    than the 250 Hz streams.
    """

    attitude_valid: bool = False
    q: F4 = Q_IDENTITY
    attitude_timestamp: int = 0
    angular_velocity_timestamp: int = 0
    gyro_bias: F3 = ZERO3
