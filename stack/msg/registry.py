"""The topic catalogue (PX4's topic names, each with its message type) and each type's schema fingerprint."""

from __future__ import annotations

import functools
import hashlib

import msgspec

from stack.msg.actuators import ActuatorMotors, ActuatorOutputs, ControlAllocatorStatus
from stack.msg.base import Message
from stack.msg.estimation import (
    EstimatorStatus,
    VehicleAngularVelocity,
    VehicleAttitude,
    VehicleGlobalPosition,
    VehicleImuStatus,
    VehicleLocalPosition,
)
from stack.msg.fixedwing import (
    ActuatorServos,
    Airspeed,
    AirspeedValidated,
    PositionControllerStatus,
    PositionSetpointTriplet,
    TecsStatus,
    Wind,
)
from stack.msg.navigation import Mission, MissionResult, NavigationRequest
from stack.msg.sensors import SensorAccel, SensorBaro, SensorGps, SensorGyro, SensorMag
from stack.msg.setpoints import (
    HoverThrustEstimate,
    ManualControlSetpoint,
    RateCtrlStatus,
    RollPitchYawrateThrustSetpoint,
    TakeoffStatus,
    TrajectorySetpoint,
    VehicleAttitudeSetpoint,
    VehicleLocalPositionSetpoint,
    VehicleRatesSetpoint,
    VehicleThrustSetpoint,
    VehicleTorqueSetpoint,
)
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import (
    ActuatorArmed,
    BatteryStatus,
    ExternalAutopilotStatus,
    HomePosition,
    MavlinkLog,
    OffboardControlMode,
    ParameterUpdate,
    TelemetryStatus,
    VehicleCommand,
    VehicleCommandAck,
    VehicleControlMode,
    VehicleLandDetected,
    VehicleStatus,
)
from stack.msg.topic import FromTools, Topic
from stack.names import suggestion


class ORB_ID:
    """The catalogue: every topic (PX4's names) with its message type. As PX4's ``# TOPICS`` lines, one type may
    serve several topics."""

    sensor_gyro = Topic(SensorGyro)
    sensor_accel = Topic(SensorAccel)
    sensor_mag = Topic(SensorMag)
    sensor_baro = Topic(SensorBaro)
    sensor_gps = Topic(SensorGps)
    vehicle_gps_position = Topic(SensorGps)
    vehicle_angular_velocity = Topic(VehicleAngularVelocity)
    vehicle_attitude = Topic(VehicleAttitude)
    vehicle_local_position = Topic(VehicleLocalPosition)
    vehicle_global_position = Topic(VehicleGlobalPosition)
    vehicle_imu_status = Topic(VehicleImuStatus)
    estimator_status = Topic(EstimatorStatus)
    trajectory_setpoint = Topic(TrajectorySetpoint, from_tools=FromTools.IN_OFFBOARD)
    vehicle_local_position_setpoint = Topic(VehicleLocalPositionSetpoint, telemetry=True)
    vehicle_attitude_setpoint = Topic(VehicleAttitudeSetpoint, from_tools=FromTools.IN_OFFBOARD)
    vehicle_rates_setpoint = Topic(VehicleRatesSetpoint, from_tools=FromTools.IN_OFFBOARD)
    roll_pitch_yawrate_thrust_setpoint = Topic(RollPitchYawrateThrustSetpoint)
    vehicle_torque_setpoint = Topic(VehicleTorqueSetpoint, from_tools=FromTools.IN_OFFBOARD)
    vehicle_thrust_setpoint = Topic(VehicleThrustSetpoint, from_tools=FromTools.IN_OFFBOARD)
    rate_ctrl_status = Topic(RateCtrlStatus, telemetry=True)
    manual_control_setpoint = Topic(ManualControlSetpoint, from_tools=FromTools.ALWAYS)
    actuator_motors = Topic(ActuatorMotors, from_tools=FromTools.IN_OFFBOARD)
    actuator_outputs = Topic(ActuatorOutputs, telemetry=True)
    actuator_outputs_sim = Topic(ActuatorOutputs)
    control_allocator_status = Topic(ControlAllocatorStatus)
    vehicle_control_mode = Topic(VehicleControlMode)
    vehicle_status = Topic(VehicleStatus)
    actuator_armed = Topic(ActuatorArmed)
    vehicle_land_detected = Topic(VehicleLandDetected)
    offboard_control_mode = Topic(OffboardControlMode, from_tools=FromTools.ALWAYS)
    telemetry_status = Topic(TelemetryStatus)
    mavlink_log = Topic(MavlinkLog)
    battery_status = Topic(BatteryStatus)
    home_position = Topic(HomePosition)
    hover_thrust_estimate = Topic(HoverThrustEstimate)
    takeoff_status = Topic(TakeoffStatus)
    vehicle_command = Topic(VehicleCommand, from_tools=FromTools.ALWAYS)
    vehicle_command_ack = Topic(VehicleCommandAck)
    parameter_update = Topic(ParameterUpdate, telemetry=True)
    sim_groundtruth = Topic(SimGroundtruth, telemetry=True)
    mission = Topic(Mission, from_tools=FromTools.ALWAYS)
    mission_result = Topic(MissionResult)
    navigation_request = Topic(NavigationRequest)
    external_autopilot_status = Topic(ExternalAutopilotStatus)
    airspeed = Topic(Airspeed)
    airspeed_validated = Topic(AirspeedValidated)
    wind = Topic(Wind)
    actuator_servos = Topic(ActuatorServos)
    position_setpoint_triplet = Topic(PositionSetpointTriplet)
    tecs_status = Topic(TecsStatus)
    position_controller_status = Topic(PositionControllerStatus)


TOPICS: dict[str, Topic] = {t.name: t for t in vars(ORB_ID).values() if isinstance(t, Topic)}
"""The catalogue by name, for the edges: keys, recordings, the CLI."""


class UnknownTopic(KeyError):
    def __str__(self) -> str:
        name = str(self.args[0])
        return f"unknown topic '{name}'{suggestion(name, TOPICS)} (see `stack topic list --all` for the catalogue)"


def message_type(topic: str) -> type[Message]:
    try:
        return TOPICS[topic].type
    except KeyError:
        raise UnknownTopic(topic) from None


def _type_text(t: msgspec.inspect.Type) -> str:
    """A version-independent spelling of a msgspec type (its repr changes between msgspec releases)."""
    if isinstance(t, msgspec.inspect.TupleType):
        return "tuple[" + ",".join(_type_text(i) for i in t.item_types) + "]"
    if isinstance(t, msgspec.inspect.StructType):
        return t.cls.__name__ + "(" + ",".join(f"{f.name}:{_type_text(f.type)}" for f in t.fields) + ")"
    if isinstance(t, msgspec.inspect.VarTupleType | msgspec.inspect.ListType):
        bounds = f"{t.min_length or 0}..{'' if t.max_length is None else t.max_length}"
        return f"{type(t).__name__[:-4].lower()}[{_type_text(t.item_type)};{bounds}]"
    return type(t).__name__.removesuffix("Type").lower()


def schema_text(msg_type: type[msgspec.Struct]) -> str:
    """Canonical text of a type's wire schema: its name and its ordered field names and types.

    Defaults and documentation are left out, so only changes that alter the wire format (or the
    meaning of a position in the array) change the fingerprint.
    """
    info = msgspec.inspect.type_info(msg_type)
    fields = ",".join(f"{f.name}:{_type_text(f.type)}" for f in info.fields)
    return f"{msg_type.__name__}({fields})"


@functools.cache
def fingerprint(msg_type: type[msgspec.Struct]) -> int:
    """Stable 64-bit schema fingerprint, identical in every process built from the same definition."""
    digest = hashlib.sha256(schema_text(msg_type).encode()).digest()
    return int.from_bytes(digest[:8], "little")
