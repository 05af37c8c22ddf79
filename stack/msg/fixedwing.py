"""Fixed-wing topics: airspeed, wind, control surfaces, the navigator's triplet and the guidance status.

Names and fields follow PX4's ``msg/Airspeed.msg``, ``AirspeedValidated.msg``, ``Wind.msg``,
``ActuatorServos.msg``, ``PositionSetpoint.msg``/``PositionSetpointTriplet.msg``, ``TecsStatus.msg`` and
``PositionControllerStatus.msg``; positions are local NED metres about home (PX4 carries lat/lon in the
triplet; here the navigator has already projected them, as the ``mission`` topic is local too).
"""

from __future__ import annotations

from typing import Annotated

import msgspec

from stack.msg.base import NAN, Message

F8 = Annotated[tuple[float, ...], msgspec.Meta(min_length=8, max_length=8)]
NAN8: tuple[float, ...] = (NAN,) * 8
SERVO_SLOTS = 8
"""Control surfaces an ``ActuatorServos`` carries (PX4 ``actuator_servos.msg`` NUM_CONTROLS)."""


class Airspeed(Message):
    """A differential-pressure airspeed sensor's reading (PX4 ``airspeed``)."""

    timestamp_sample: int = 0
    device_id: int = 0
    indicated_airspeed_m_s: float = NAN
    true_airspeed_m_s: float = NAN
    differential_pressure_pa: float = NAN
    air_temperature_celsius: float = NAN
    confidence: float = 0.0


AIRSPEED_TIMEOUT_US = 1_000_000
"""An ``airspeed_validated`` older than this is not used (PX4 FixedwingAttitudeControl
``get_airspeed_and_update_scaling``)."""


class AirspeedValidated(Message):
    """The airspeed the controllers use (PX4 ``airspeed_validated``, published by airspeed_selector).

    NaN speeds: no valid airspeed (the controllers then fly on FW_THR_TRIM and the nominal speed).
    """

    timestamp_sample: int = 0
    indicated_airspeed_m_s: float = NAN
    calibrated_airspeed_m_s: float = NAN
    true_airspeed_m_s: float = NAN
    calibrated_ground_minus_wind_m_s: float = NAN
    true_ground_minus_wind_m_s: float = NAN
    airspeed_sensor_measurement_valid: bool = False
    selected_airspeed_index: int = -1
    airspeed_derivative_filtered: float = 0.0
    throttle_filtered: float = 0.0
    pitch_filtered: float = 0.0


class Wind(Message):
    """The wind estimate, NED horizontal (PX4 ``wind``); variances in (m/s)²."""

    timestamp_sample: int = 0
    windspeed_north: float = NAN
    windspeed_east: float = NAN
    variance_north: float = NAN
    variance_east: float = NAN
    tas_innov: float = NAN
    tas_innov_var: float = NAN
    tas_scale_raw: float = NAN
    tas_scale_validated: float = NAN
    source: int = 0


class ActuatorServos(Message):
    """Control-surface commands in [−1, 1] (PX4 ``actuator_servos``); centred (0) when disarmed, NaN = unused.

    Servo order here: 0 aileron (+: roll right), 1 elevator (+: nose up), 2 rudder (+: nose right).
    """

    NAN_MEANS_NOT_CONTROLLED = True

    timestamp_sample: int = 0
    control: F8 = NAN8


class PositionSetpoint(msgspec.Struct, array_like=True, gc=False):
    """One position setpoint of the triplet (PX4 ``position_setpoint``), local NED about home."""

    NAN_MEANS_NOT_CONTROLLED = True

    valid: bool = False
    type: int = 0
    x: float = NAN
    y: float = NAN
    z: float = NAN
    vx: float = NAN
    vy: float = NAN
    vz: float = NAN
    yaw: float = NAN
    loiter_radius: float = NAN
    loiter_direction_counter_clockwise: bool = False
    acceptance_radius: float = NAN
    cruising_speed: float = NAN
    cruising_throttle: float = NAN
    lat: float = NAN
    lon: float = NAN
    alt: float = NAN

    SETPOINT_TYPE_POSITION = 0
    SETPOINT_TYPE_VELOCITY = 1
    SETPOINT_TYPE_LOITER = 2
    SETPOINT_TYPE_TAKEOFF = 3
    SETPOINT_TYPE_LAND = 4
    SETPOINT_TYPE_IDLE = 5


class PositionSetpointTriplet(Message):
    """Previous, current and next setpoints for the position controller (PX4 ``position_setpoint_triplet``)."""

    previous: PositionSetpoint = msgspec.field(default_factory=PositionSetpoint)
    current: PositionSetpoint = msgspec.field(default_factory=PositionSetpoint)
    next: PositionSetpoint = msgspec.field(default_factory=PositionSetpoint)


class TecsStatus(Message):
    """TECS' setpoints, rates and outputs (PX4 ``tecs_status``)."""

    altitude_sp: float = NAN
    altitude_reference: float = NAN
    height_rate_reference: float = NAN
    height_rate_direct: float = NAN
    height_rate_setpoint: float = NAN
    height_rate: float = NAN
    equivalent_airspeed_sp: float = NAN
    true_airspeed_sp: float = NAN
    true_airspeed_filtered: float = NAN
    true_airspeed_derivative_sp: float = NAN
    true_airspeed_derivative: float = NAN
    true_airspeed_derivative_raw: float = NAN
    total_energy_rate_sp: float = NAN
    total_energy_rate: float = NAN
    total_energy_balance_rate_sp: float = NAN
    total_energy_balance_rate: float = NAN
    throttle_integ: float = NAN
    pitch_integ: float = NAN
    throttle_sp: float = NAN
    pitch_sp_rad: float = NAN
    throttle_trim: float = NAN
    underspeed_ratio: float = NAN
    fast_descend_ratio: float = NAN


class PositionControllerStatus(Message):
    """The lateral guidance's state (PX4 ``position_controller_status``)."""

    nav_roll: float = NAN
    nav_pitch: float = NAN
    nav_bearing: float = NAN
    target_bearing: float = NAN
    xtrack_error: float = NAN
    wp_dist: float = NAN
    acceptance_radius: float = NAN
    yaw_acceptance: float = NAN
    altitude_acceptance: float = NAN
    type: int = 0
