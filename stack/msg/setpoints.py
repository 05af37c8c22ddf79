"""The setpoint chain from trajectory to torque (PX4 ``TrajectorySetpoint`` ... ``VehicleThrustSetpoint``)."""

from __future__ import annotations

from enum import IntEnum

from stack.msg.base import F3, F4, NAN, NAN3, Q_IDENTITY, ZERO3, Message


class TrajectorySetpoint(Message):
    """Position/velocity/acceleration setpoint in NED; NaN components are not controlled."""

    NAN_MEANS_NOT_CONTROLLED = True

    position: F3 = NAN3
    velocity: F3 = NAN3
    acceleration: F3 = NAN3
    jerk: F3 = NAN3
    yaw: float = NAN
    yawspeed: float = NAN


class VehicleLocalPositionSetpoint(Message):
    """What the position controller is tracking and commanding (telemetry)."""

    NAN_MEANS_NOT_CONTROLLED = True

    x: float = NAN
    y: float = NAN
    z: float = NAN
    vx: float = NAN
    vy: float = NAN
    vz: float = NAN
    acceleration: F3 = NAN3
    thrust: F3 = NAN3
    yaw: float = NAN
    yawspeed: float = NAN


class VehicleAttitudeSetpoint(Message):
    """Desired attitude (body FRD → NED) and normalised body thrust (multicopter: (0, 0, −collective); fixed wing:
    (throttle, 0, 0)).

    Fixed wing only: ``fw_control_yaw_wheel`` asks fw_att_control to steer the heading of ``q_d`` with the wheel
    controller (runway takeoff and landing, auto modes; PX4's ``fw_control_yaw``), ``reset_integral`` to restart
    its roll, pitch and yaw integrators (PX4's ``roll/pitch/yaw_reset_integral``)."""

    NAN_MEANS_NOT_CONTROLLED = True

    yaw_sp_move_rate: float = NAN
    q_d: F4 = Q_IDENTITY
    thrust_body: F3 = ZERO3
    fw_control_yaw_wheel: bool = False
    reset_integral: bool = False


class RollPitchYawrateThrustSetpoint(Message):
    """The RotorS interface (``mav_msgs/RollPitchYawrateThrust``) in the stack's frames.

    Roll and pitch [rad] are the angles of R_d = Rz(yaw)·Rx(roll)·Ry(pitch) about the current heading, yaw_rate
    [rad/s] the commanded heading rate and thrust [N] the collective thrust magnitude along −z body. Unlike
    mav_msgs (body FLU, world ENU), they are FRD/NED: pitch + is nose up and yaw_rate + is clockwise seen from above,
    so RotorS' pitch and yaw rate are the negatives of these. Every field must be finite.
    """

    NAN_MEANS_NOT_CONTROLLED = True

    timestamp_sample: int = 0
    roll: float = 0.0
    pitch: float = 0.0
    yaw_rate: float = 0.0
    thrust: float = 0.0


class VehicleRatesSetpoint(Message):
    """Desired body rates [rad/s]; NaN on an axis holds the current rate."""

    NAN_MEANS_NOT_CONTROLLED = True

    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    thrust_body: F3 = ZERO3
    reset_integral: bool = False


class VehicleTorqueSetpoint(Message):
    """Normalised torque about body x, y, z."""

    NAN_MEANS_NOT_CONTROLLED = True

    timestamp_sample: int = 0
    xyz: F3 = ZERO3


class VehicleThrustSetpoint(Message):
    """Normalised thrust in body frame, each in [−1, 1]; multicopter thrust is negative z."""

    NAN_MEANS_NOT_CONTROLLED = True

    timestamp_sample: int = 0
    xyz: F3 = ZERO3


class RateCtrlStatus(Message):
    """Rate-controller integrator states (normalised torque)."""

    rollspeed_integ: float = 0.0
    pitchspeed_integ: float = 0.0
    yawspeed_integ: float = 0.0


class ManualControlSetpoint(Message):
    """Pilot sticks in [−1, 1]: throttle −1 is minimum, pitch +1 is nose down, yaw + is clockwise."""

    SOURCE_UNKNOWN = 0
    SOURCE_RC = 1
    SOURCE_MAVLINK_0 = 2

    timestamp_sample: int = 0
    valid: bool = False
    data_source: int = 0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    throttle: float = -1.0
    flaps: float = 0.0
    aux1: float = 0.0
    aux2: float = 0.0
    aux3: float = 0.0
    aux4: float = 0.0
    aux5: float = 0.0
    aux6: float = 0.0
    sticks_moving: bool = False
    buttons: int = 0


class HoverThrustEstimate(Message):
    """Collective thrust that holds altitude (PX4 ``HoverThrustEstimate``), normalised."""

    timestamp_sample: int = 0
    hover_thrust: float = NAN
    hover_thrust_var: float = NAN
    accel_innov: float = NAN
    accel_innov_var: float = NAN
    accel_innov_test_ratio: float = NAN
    accel_noise_var: float = NAN
    valid: bool = False


class TakeoffStatus(Message):
    """The position controller's takeoff stage (PX4 ``TakeoffStatus``) and current tilt limit [rad]."""

    TAKEOFF_STATE_UNINITIALIZED = 0
    TAKEOFF_STATE_DISARMED = 1
    TAKEOFF_STATE_SPOOLUP = 2
    TAKEOFF_STATE_READY_FOR_TAKEOFF = 3
    TAKEOFF_STATE_RAMPUP = 4
    TAKEOFF_STATE_FLIGHT = 5

    takeoff_state: int = TAKEOFF_STATE_UNINITIALIZED
    tilt_limit: float = NAN


class TakeoffState(IntEnum):
    """The position controller's takeoff state (PX4 ``Takeoff.hpp``), numbered as ``takeoff_status`` numbers it."""

    DISARMED = TakeoffStatus.TAKEOFF_STATE_DISARMED
    SPOOLUP = TakeoffStatus.TAKEOFF_STATE_SPOOLUP
    READY_FOR_TAKEOFF = TakeoffStatus.TAKEOFF_STATE_READY_FOR_TAKEOFF
    RAMPUP = TakeoffStatus.TAKEOFF_STATE_RAMPUP
    FLIGHT = TakeoffStatus.TAKEOFF_STATE_FLIGHT
