"""System state and commands (PX4 ``VehicleStatus``, ``VehicleControlMode``, ``VehicleCommand``...)."""

from __future__ import annotations

from enum import IntEnum

import msgspec

from stack.msg.base import NAN, Message


class VehicleControlMode(Message):
    """Which loops run, set by the commander from the navigation state; the controllers obey it."""

    flag_armed: bool = False
    flag_multicopter_position_control_enabled: bool = False
    flag_control_manual_enabled: bool = False
    flag_control_auto_enabled: bool = False
    flag_control_offboard_enabled: bool = False
    flag_control_position_enabled: bool = False
    flag_control_velocity_enabled: bool = False
    flag_control_altitude_enabled: bool = False
    flag_control_climb_rate_enabled: bool = False
    flag_control_acceleration_enabled: bool = False
    flag_control_attitude_enabled: bool = False
    flag_control_rates_enabled: bool = False
    flag_control_allocation_enabled: bool = False
    flag_control_termination_enabled: bool = False
    source_id: int = 0
    # PX4's rattitude mode (removed from PX4 in 2021, kept here): sticks beyond MC_RATT_TH command rates.
    flag_control_rattitude_enabled: bool = False
    # The RotorS interface (not in PX4): roll, pitch, yaw rate and thrust from roll_pitch_yawrate_thrust_setpoint.
    flag_control_rpyt_enabled: bool = False


class VehicleStatus(Message):
    """Arming and navigation state (PX4 ``VehicleStatus`` v2, the fields a multicopter uses)."""

    ARMING_STATE_DISARMED = 1
    ARMING_STATE_ARMED = 2

    NAVIGATION_STATE_MANUAL = 0
    NAVIGATION_STATE_ALTCTL = 1
    NAVIGATION_STATE_POSCTL = 2
    NAVIGATION_STATE_AUTO_MISSION = 3
    NAVIGATION_STATE_AUTO_LOITER = 4
    NAVIGATION_STATE_AUTO_RTL = 5
    NAVIGATION_STATE_ACRO = 10
    NAVIGATION_STATE_DESCEND = 12
    NAVIGATION_STATE_TERMINATION = 13
    NAVIGATION_STATE_OFFBOARD = 14
    NAVIGATION_STATE_STAB = 15
    NAVIGATION_STATE_AUTO_TAKEOFF = 17
    NAVIGATION_STATE_AUTO_LAND = 18
    # PX4's first external mode slot (a mode registered from outside, as ROS 2 modes are): the RotorS interface.
    NAVIGATION_STATE_EXTERNAL1 = 23
    # Not in current PX4 (removed with rattitude); a free number outside PX4's used range.
    NAVIGATION_STATE_RATTITUDE = 31

    VEHICLE_TYPE_ROTARY_WING = 1
    VEHICLE_TYPE_FIXED_WING = 2

    timestamp_sample: int = 0
    armed_time: int = 0
    takeoff_time: int = 0
    arming_state: int = ARMING_STATE_DISARMED
    latest_arming_reason: int = 0
    latest_disarming_reason: int = 0
    nav_state_timestamp: int = 0
    nav_state_user_intention: int = NAVIGATION_STATE_MANUAL
    nav_state: int = NAVIGATION_STATE_MANUAL
    executor_in_charge: int = 0
    valid_nav_states_mask: int = 0
    can_set_nav_states_mask: int = 0
    failure_detector_status: int = 0
    hil_state: int = 0
    vehicle_type: int = VEHICLE_TYPE_ROTARY_WING
    failsafe: bool = False
    failsafe_and_user_took_over: bool = False
    failsafe_defer_state: int = 0
    gcs_connection_lost: bool = False
    gcs_connection_lost_counter: int = 0
    high_latency_data_link_lost: bool = False
    system_type: int = 2
    system_id: int = 1
    component_id: int = 1
    safety_button_available: bool = False
    safety_off: bool = True
    power_input_valid: bool = True
    usb_connected: bool = False
    pre_flight_checks_pass: bool = False
    control_lost_modules: list[str] = msgspec.field(default_factory=list)
    """The control chain's dead or silent modules (not in PX4, whose loops share one process)."""
    lost_hosts: list[str] = msgspec.field(default_factory=list)
    """The vehicle's hosts whose beats stopped (not in PX4, which runs on one board; stack.bus.host_beats)."""


class ActuatorArmed(Message):
    """Arming state as the output drivers see it."""

    armed: bool = False
    prearmed: bool = False
    ready_to_arm: bool = False
    lockdown: bool = False
    kill: bool = False
    termination: bool = False
    in_esc_calibration_mode: bool = False


class VehicleCommand(Message):
    """A MAVLink-style command (MAV_CMD ids); params 5 and 6 are float64 for latitude/longitude."""

    RECEIVER_CHECKS_VALUES = True

    VEHICLE_CMD_NAV_WAYPOINT = 16
    VEHICLE_CMD_NAV_LOITER_UNLIM = 17
    VEHICLE_CMD_NAV_RETURN_TO_LAUNCH = 20
    VEHICLE_CMD_NAV_LAND = 21
    VEHICLE_CMD_NAV_TAKEOFF = 22
    VEHICLE_CMD_DO_SET_MODE = 176
    VEHICLE_CMD_DO_FLIGHTTERMINATION = 185
    VEHICLE_CMD_DO_REPOSITION = 192
    VEHICLE_CMD_DO_SET_MISSION_CURRENT = 224
    VEHICLE_CMD_MISSION_START = 300
    VEHICLE_CMD_COMPONENT_ARM_DISARM = 400
    VEHICLE_CMD_INJECT_FAILURE = 420
    FAILURE_UNIT_SENSOR_GYRO = 0
    FAILURE_UNIT_SENSOR_ACCEL = 1
    FAILURE_UNIT_SENSOR_MAG = 2
    FAILURE_UNIT_SENSOR_BARO = 3
    FAILURE_UNIT_SENSOR_GPS = 4
    FAILURE_TYPE_OK = 0
    FAILURE_TYPE_OFF = 1
    # PX4-internal ids (above 65535): SET_NAV_STATE is PX4's; DO_REPOSITION_LOCAL is ours (DO_REPOSITION
    # with param5/6/7 the local north, east, down in metres).
    VEHICLE_CMD_SET_NAV_STATE = 100001
    VEHICLE_CMD_DO_REPOSITION_LOCAL = 100192
    ARMING_ACTION_DISARM = 0
    ARMING_ACTION_ARM = 1
    ARM_FORCE_MAGIC = 21196

    param1: float = NAN
    param2: float = NAN
    param3: float = NAN
    param4: float = NAN
    param5: float = NAN
    param6: float = NAN
    param7: float = NAN
    command: int = 0
    target_system: int = 1
    target_component: int = 1
    source_system: int = 255
    source_component: int = 0
    confirmation: int = 0
    from_external: bool = True


class VehicleCommandAck(Message):
    """The answer to a ``vehicle_command``; ``reason`` (our addition) says why in words."""

    VEHICLE_CMD_RESULT_ACCEPTED = 0
    VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED = 1
    VEHICLE_CMD_RESULT_DENIED = 2
    VEHICLE_CMD_RESULT_UNSUPPORTED = 3
    VEHICLE_CMD_RESULT_FAILED = 4
    VEHICLE_CMD_RESULT_IN_PROGRESS = 5
    VEHICLE_CMD_RESULT_CANCELLED = 6

    command: int = 0
    result: int = 0
    result_param1: int = 0
    result_param2: int = 0
    target_system: int = 0
    target_component: int = 0
    from_external: bool = False
    reason: str = ""


def _short_names(cls: type, prefix: str) -> dict[int, str]:
    """Constant value → name without ``prefix``, from a message class's ``PREFIX_NAME = value`` attributes."""
    return {v: k.removeprefix(prefix) for k, v in vars(cls).items() if k.startswith(prefix) and isinstance(v, int)}


COMMAND_NAMES = _short_names(VehicleCommand, "VEHICLE_CMD_")
"""Command id → MAVLink's MAV_CMD name without the prefix (``NAV_LAND``), for the commands the stack knows."""
RESULT_NAMES = _short_names(VehicleCommandAck, "VEHICLE_CMD_RESULT_")
"""Acknowledgement result → MAVLink's MAV_RESULT name without the prefix (``TEMPORARILY_REJECTED``)."""


def command_label(command: int) -> str:
    """A command for people: ``NAV_LAND (21)``, or the bare number of a command the stack does not know."""
    name = COMMAND_NAMES.get(command)
    return f"{name} ({command})" if name else str(command)


class ParameterUpdate(Message):
    """Published whenever a parameter value changes (``instance`` counts notifications)."""

    instance: int = 0
    get_count: int = 0
    set_count: int = 0
    find_count: int = 0
    export_count: int = 0
    active: int = 0
    changed: int = 0
    custom_default: int = 0


class VehicleLandDetected(Message):
    """Land detector output (PX4 ``VehicleLandDetected``): the stages from ground contact to landed."""

    freefall: bool = False
    ground_contact: bool = True
    maybe_landed: bool = True
    landed: bool = True
    in_ground_effect: bool = True
    in_descend: bool = False
    has_low_throttle: bool = False
    vertical_movement: bool = False
    horizontal_movement: bool = False
    rotational_movement: bool = False
    close_to_ground_or_skipped_check: bool = True
    at_rest: bool = True


class OffboardControlMode(Message):
    """Which setpoints an offboard controller streams (PX4 ``OffboardControlMode``); also its proof of life."""

    position: bool = False
    velocity: bool = False
    acceleration: bool = False
    attitude: bool = False
    body_rate: bool = False
    thrust_and_torque: bool = False
    direct_actuator: bool = False


class MavlinkLog(Message):
    """A message for the operator (PX4 ``MavlinkLog``): the ground-station links send it as STATUSTEXT.
    ``severity`` is MAVLink's MAV_SEVERITY (PX4: the kernel log levels, the same numbers)."""

    SEVERITY_EMERGENCY = 0
    SEVERITY_ALERT = 1
    SEVERITY_CRITICAL = 2
    SEVERITY_ERROR = 3
    SEVERITY_WARNING = 4
    SEVERITY_NOTICE = 5
    SEVERITY_INFO = 6
    SEVERITY_DEBUG = 7

    text: str = ""
    severity: int = SEVERITY_INFO


class TelemetryStatus(Message):
    """A command link's heartbeat (the subset of PX4 ``TelemetryStatus`` the commander uses)."""

    LINK_TYPE_GENERIC = 0
    LINK_TYPE_UDP = 1

    type: int = LINK_TYPE_GENERIC
    heartbeat_type_gcs: bool = False
    heartbeat_type_onboard_controller: bool = False


class BatteryStatus(Message):
    """Battery state (PX4 ``BatteryStatus`` fields a multicopter uses); ``remaining`` in [0, 1]."""

    WARNING_NONE = 0
    WARNING_LOW = 1
    WARNING_CRITICAL = 2
    WARNING_EMERGENCY = 3
    WARNING_FAILED = 4

    connected: bool = False
    voltage_v: float = 0.0
    current_a: float = -1.0
    current_average_a: float = -1.0
    discharged_mah: float = -1.0
    remaining: float = -1.0
    scale: float = 1.0
    time_remaining_s: float = float("nan")
    temperature: float = float("nan")
    cell_count: int = 0
    capacity: float = 0.0
    warning: int = WARNING_NONE


class BatteryWarning(IntEnum):
    """``battery_status.warning``, ordered by severity."""

    NONE = BatteryStatus.WARNING_NONE
    LOW = BatteryStatus.WARNING_LOW
    CRITICAL = BatteryStatus.WARNING_CRITICAL
    EMERGENCY = BatteryStatus.WARNING_EMERGENCY
    FAILED = BatteryStatus.WARNING_FAILED


class HomePosition(Message):
    """Home: where the vehicle armed, in local NED and geodetic coordinates (PX4 ``HomePosition``)."""

    lat: float = float("nan")
    lon: float = float("nan")
    alt: float = float("nan")
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = 0.0
    valid_alt: bool = False
    valid_hpos: bool = False
    valid_lpos: bool = False
    manual_home: bool = False
    update_count: int = 0


class ExternalAutopilotStatus(Message):
    """An external autopilot the stack flies through (a PX4 Pixhawk over MAVLink, module ``pixhawk``).

    Its own HEARTBEAT is the truth about its arming and mode (``custom_mode`` as PX4 encodes it, ``mode`` its
    name, see :mod:`stack.mavlink.px4_modes`); ``armable`` is SYS_STATUS's pre-arm check bit (True when it
    is not reported and the autopilot is in standby). ``in_control``: it is armed in Offboard and flies the
    stack's setpoints. ``refusals`` counts the arming and Offboard requests it refused, ``refusal`` says
    the last one and why. No PX4 topic describes another autopilot; this one follows PX4's naming.
    """

    connected: bool = False
    system_id: int = 0
    component_id: int = 0
    autopilot: int = 0
    armed: bool = False
    custom_mode: int = 0
    mode: str = ""
    system_status: int = 0
    armable: bool = False
    offboard: bool = False
    in_control: bool = False
    refusals: int = 0
    refusal: str = ""
    link_losses: int = 0
    link_quality: float = 0.0
