"""The topic catalogue: topic names (PX4's) → message types, and each type's schema fingerprint."""

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
from stack.names import suggestion

# Like PX4's "# TOPICS" lines, one type may serve several topics.
TOPICS: dict[str, type[Message]] = {
    "sensor_gyro": SensorGyro,
    "sensor_accel": SensorAccel,
    "sensor_mag": SensorMag,
    "sensor_baro": SensorBaro,
    "sensor_gps": SensorGps,
    "vehicle_gps_position": SensorGps,
    "vehicle_angular_velocity": VehicleAngularVelocity,
    "vehicle_attitude": VehicleAttitude,
    "vehicle_local_position": VehicleLocalPosition,
    "vehicle_global_position": VehicleGlobalPosition,
    "vehicle_imu_status": VehicleImuStatus,
    "estimator_status": EstimatorStatus,
    "trajectory_setpoint": TrajectorySetpoint,
    "vehicle_local_position_setpoint": VehicleLocalPositionSetpoint,
    "vehicle_attitude_setpoint": VehicleAttitudeSetpoint,
    "vehicle_rates_setpoint": VehicleRatesSetpoint,
    "roll_pitch_yawrate_thrust_setpoint": RollPitchYawrateThrustSetpoint,
    "vehicle_torque_setpoint": VehicleTorqueSetpoint,
    "vehicle_thrust_setpoint": VehicleThrustSetpoint,
    "rate_ctrl_status": RateCtrlStatus,
    "manual_control_setpoint": ManualControlSetpoint,
    "actuator_motors": ActuatorMotors,
    "actuator_outputs": ActuatorOutputs,
    "actuator_outputs_sim": ActuatorOutputs,
    "control_allocator_status": ControlAllocatorStatus,
    "vehicle_control_mode": VehicleControlMode,
    "vehicle_status": VehicleStatus,
    "actuator_armed": ActuatorArmed,
    "vehicle_land_detected": VehicleLandDetected,
    "offboard_control_mode": OffboardControlMode,
    "telemetry_status": TelemetryStatus,
    "mavlink_log": MavlinkLog,
    "battery_status": BatteryStatus,
    "home_position": HomePosition,
    "hover_thrust_estimate": HoverThrustEstimate,
    "takeoff_status": TakeoffStatus,
    "vehicle_command": VehicleCommand,
    "vehicle_command_ack": VehicleCommandAck,
    "parameter_update": ParameterUpdate,
    "sim_groundtruth": SimGroundtruth,
    "mission": Mission,
    "mission_result": MissionResult,
    "navigation_request": NavigationRequest,
    "external_autopilot_status": ExternalAutopilotStatus,
    "airspeed": Airspeed,
    "airspeed_validated": AirspeedValidated,
    "wind": Wind,
    "actuator_servos": ActuatorServos,
    "position_setpoint_triplet": PositionSetpointTriplet,
    "tecs_status": TecsStatus,
    "position_controller_status": PositionControllerStatus,
}


class UnknownTopic(KeyError):
    def __str__(self) -> str:
        name = str(self.args[0])
        return f"unknown topic '{name}'{suggestion(name, TOPICS)} (see `stack topic list --all` for the catalogue)"


def message_type(topic: str) -> type[Message]:
    try:
        return TOPICS[topic]
    except KeyError:
        raise UnknownTopic(topic) from None


def register_topic(topic: str, msg_type: type[Message]) -> None:
    """Add a topic to the catalogue (for topics defined outside this package)."""
    existing = TOPICS.get(topic)
    if existing is not None and existing is not msg_type:
        raise ValueError(f"topic '{topic}' is already registered with type {existing.__name__}")
    TOPICS[topic] = msg_type


def type_by_name(name: str) -> type[Message]:
    for t in TOPICS.values():
        if t.__name__ == name:
            return t
    raise KeyError(name)


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
