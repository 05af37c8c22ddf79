"""Offboard control from a link: SET_POSITION_TARGET_LOCAL_NED and SET_ATTITUDE_TARGET → the stack's setpoints and
``offboard_control_mode``, PX4's proof of life (I/O-free).

As PX4's receiver (``src/modules/mavlink/mavlink_receiver.cpp``): every valid setpoint message publishes
``offboard_control_mode`` saying what it controls (the commander needs it to arm in or switch to Offboard, and
leaves Offboard after COM_OF_LOSS_T without it), and the setpoint itself is published only while the vehicle is in
Offboard. SET_POSITION_TARGET_LOCAL_NED gives position, velocity and acceleration per axis (an axis whose
POSITION_TARGET_TYPEMASK bit is set is NaN, "not controlled"), yaw and yaw rate, in MAV_FRAME_LOCAL_NED, or in
MAV_FRAME_BODY_NED for velocity and acceleration (rotated by the vehicle's heading); force setpoints and body-frame
positions are refused. SET_ATTITUDE_TARGET gives an attitude (``vehicle_attitude_setpoint``) or, with the attitude
ignored, body rates (``vehicle_rates_setpoint``), with the collective thrust in [0, 1]. A NaN or infinite value in
a field that is used, a quaternion that is not a unit one, or a thrust out of range is refused.

:class:`OffboardRelay` keeps the proof of life on the stack's clock: while the client streams (at PX4's 2 Hz at
least, judged on the wall clock), the last setpoint and ``offboard_control_mode`` are republished every
REPUBLISH_US of wall time, stamped with the stack's time. In lockstep the simulation runs ~10× faster than the
wall: a client's 20 Hz stream would otherwise be 0.5 s of simulated time apart, as old as mc_pos_control's
setpoint timeout. When the client stops, so does the relay, and COM_OF_LOSS_T runs on the stack's clock.
"""

from __future__ import annotations

import math
from typing import Any

from pymavlink.dialects.v20 import common as mavlink2

from stack.mathlib import quaternion as quat
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TrajectorySetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import OffboardControlMode
from stack.msg.topic import Topic

NAN = math.nan
PROOF_OF_LIFE_US = 500_000
"""PX4 wants offboard setpoints at 2 Hz at least (``docs/en/flight_modes/offboard.md``)."""
REPUBLISH_US = 20_000
QUATERNION_NORM_TOLERANCE = 0.05
RATE_MAX_RAD_S = 20.0

P = mavlink2  # POSITION_TARGET_TYPEMASK_* / ATTITUDE_TARGET_TYPEMASK_*
POSITION_IGNORE = (
    P.POSITION_TARGET_TYPEMASK_X_IGNORE,
    P.POSITION_TARGET_TYPEMASK_Y_IGNORE,
    P.POSITION_TARGET_TYPEMASK_Z_IGNORE,
)
VELOCITY_IGNORE = (
    P.POSITION_TARGET_TYPEMASK_VX_IGNORE,
    P.POSITION_TARGET_TYPEMASK_VY_IGNORE,
    P.POSITION_TARGET_TYPEMASK_VZ_IGNORE,
)
ACCEL_IGNORE = (
    P.POSITION_TARGET_TYPEMASK_AX_IGNORE,
    P.POSITION_TARGET_TYPEMASK_AY_IGNORE,
    P.POSITION_TARGET_TYPEMASK_AZ_IGNORE,
)
RATE_IGNORE = (
    P.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE,
    P.ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE,
    P.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE,
)

Setpoint = TrajectorySetpoint | VehicleAttitudeSetpoint | VehicleRatesSetpoint


class Refused(ValueError):
    """A setpoint that is not published; the message says why."""


def _axes(values: tuple[float, float, float], mask: int, bits: tuple[int, int, int], what: str) -> tuple[float, ...]:
    out = []
    for value, bit, axis in zip(values, bits, "xyz", strict=True):
        if mask & bit:
            out.append(NAN)
        elif not math.isfinite(value):
            raise Refused(f"{what} {axis} is {value}")
        else:
            out.append(float(value))
    return tuple(out)


def _rotate_yaw(v: tuple[float, ...], heading: float) -> tuple[float, float, float]:
    c, s = math.cos(heading), math.sin(heading)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


def position_target(msg: Any, heading: float, now_us: int) -> tuple[TrajectorySetpoint, OffboardControlMode]:
    """SET_POSITION_TARGET_LOCAL_NED; ``heading`` the vehicle's [rad] for MAV_FRAME_BODY_NED."""
    mask = msg.type_mask
    if mask & P.POSITION_TARGET_TYPEMASK_FORCE_SET:
        raise Refused("force setpoints are not supported")
    position = _axes((msg.x, msg.y, msg.z), mask, POSITION_IGNORE, "position")
    velocity = _axes((msg.vx, msg.vy, msg.vz), mask, VELOCITY_IGNORE, "velocity")
    accel = _axes((msg.afx, msg.afy, msg.afz), mask, ACCEL_IGNORE, "acceleration")
    if msg.coordinate_frame == P.MAV_FRAME_BODY_NED:
        if not all(math.isnan(p) for p in position):
            raise Refused("positions in MAV_FRAME_BODY_NED are not supported")
        if not math.isfinite(heading):
            raise Refused("no heading to turn a body-frame setpoint with")
        velocity = _rotate_yaw(velocity, heading)
        accel = _rotate_yaw(accel, heading)
    elif msg.coordinate_frame != P.MAV_FRAME_LOCAL_NED:
        raise Refused(f"frame {msg.coordinate_frame} is not supported (MAV_FRAME_LOCAL_NED, MAV_FRAME_BODY_NED)")
    yaw = NAN if mask & P.POSITION_TARGET_TYPEMASK_YAW_IGNORE else msg.yaw
    yaw_rate = NAN if mask & P.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE else msg.yaw_rate
    for name, value in (("yaw", yaw), ("yaw rate", yaw_rate)):
        if math.isinf(value):
            raise Refused(f"{name} is {value}")
    given = [any(math.isfinite(v) for v in axes) for axes in (position, velocity, accel)]
    if not any(given):
        raise Refused("no position, velocity or acceleration given")
    setpoint = TrajectorySetpoint(
        timestamp=now_us, position=position, velocity=velocity, acceleration=accel, yaw=yaw, yawspeed=yaw_rate
    )
    mode = OffboardControlMode(timestamp=now_us, position=given[0], velocity=given[1], acceleration=given[2])
    return setpoint, mode


def attitude_target(
    msg: Any, now_us: int
) -> tuple[VehicleAttitudeSetpoint | VehicleRatesSetpoint, OffboardControlMode]:
    """SET_ATTITUDE_TARGET."""
    mask = msg.type_mask
    if mask & P.ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE:
        raise Refused("a thrust must be given")
    thrust = msg.thrust
    if not (math.isfinite(thrust) and 0.0 <= thrust <= 1.0):
        raise Refused(f"thrust {thrust} is outside 0..1")
    thrust_body = (0.0, 0.0, -float(thrust))
    if not mask & P.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE:
        q = tuple(float(v) for v in msg.q)
        if not quat.is_finite(q) or abs(quat.norm(q) - 1.0) > QUATERNION_NORM_TOLERANCE:  # type: ignore[arg-type]
            raise Refused(f"attitude {q} is not a unit quaternion")
        setpoint: Any = VehicleAttitudeSetpoint(timestamp=now_us, q_d=quat.normalized(q), thrust_body=thrust_body)  # type: ignore[arg-type]
        return setpoint, OffboardControlMode(timestamp=now_us, attitude=True)
    rates = _axes((msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate), mask, RATE_IGNORE, "body rate")
    if any(abs(r) > RATE_MAX_RAD_S for r in rates if math.isfinite(r)):
        raise Refused(f"body rates {rates} beyond {RATE_MAX_RAD_S} rad/s")
    setpoint = VehicleRatesSetpoint(
        timestamp=now_us, roll=rates[0], pitch=rates[1], yaw=rates[2], thrust_body=thrust_body
    )
    return setpoint, OffboardControlMode(timestamp=now_us, body_rate=True)


SETPOINT_TOPICS: dict[type, Topic] = {
    TrajectorySetpoint: ORB_ID.trajectory_setpoint,
    VehicleAttitudeSetpoint: ORB_ID.vehicle_attitude_setpoint,
    VehicleRatesSetpoint: ORB_ID.vehicle_rates_setpoint,
}


class OffboardRelay:
    """The last setpoint a client streamed, republished on the stack's clock while the client keeps streaming."""

    def __init__(self) -> None:
        self._setpoint: Setpoint | None = None
        self._mode: OffboardControlMode | None = None
        self._received_us = 0
        self._sent_us = 0

    def on_setpoint(self, setpoint: Setpoint, mode: OffboardControlMode, now_wall_us: int) -> None:
        self._setpoint, self._mode = setpoint, mode
        self._received_us = now_wall_us
        self._sent_us = 0

    def alive(self, now_wall_us: int) -> bool:
        return self._setpoint is not None and now_wall_us - self._received_us <= PROOF_OF_LIFE_US

    def due(self, now_wall_us: int, stamp_us: int, in_offboard: bool) -> list[tuple[Topic, Any]]:
        """(topic, message) to publish now, stamped ``stamp_us``: the proof of life, and the setpoint in Offboard."""
        if not self.alive(now_wall_us) or now_wall_us - self._sent_us < REPUBLISH_US:
            return []
        assert self._setpoint is not None and self._mode is not None
        self._sent_us = now_wall_us
        self._mode.timestamp = stamp_us
        out: list[tuple[Topic, Any]] = [(ORB_ID.offboard_control_mode, self._mode)]
        if in_offboard:
            self._setpoint.timestamp = stamp_us
            out.append((SETPOINT_TOPICS[type(self._setpoint)], self._setpoint))
        return out
