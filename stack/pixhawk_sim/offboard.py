"""SET_ATTITUDE_TARGET as PX4's ``MavlinkReceiver::handle_message_set_attitude_target`` reads it for a multicopter.

``type_mask`` (ATTITUDE_TARGET_TYPEMASK): with ATTITUDE_IGNORE (128) clear the message is an attitude setpoint
(quaternion w, x, y, z rotating body FRD into NED, with the body yaw rate as yaw feed-forward unless its ignore bit
4 is set); otherwise a body-rate setpoint (roll 1, pitch 2, yaw 4 ignore bits; an ignored axis is NaN, which the
rate controller reads as "hold the current rate"). ``thrust`` is the normalised collective 0..1, which PX4 turns
into the body thrust vector (0, 0, −thrust) (FRD: up is −z); THROTTLE_IGNORE (64) keeps the previous thrust.
A message with every setpoint ignored carries nothing to fly but is still proof of life, as in PX4.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from pymavlink.dialects.v20 import common as mavlink

from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.vector import Vec3

_RATE_IGNORE = (
    mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE,
    mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE,
    mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE,
)
_ALL_RATES_IGNORED = sum(_RATE_IGNORE)


class OffboardSetpoint(NamedTuple):
    """What Offboard flies: an attitude (``q`` finite) or body rates, and the body thrust."""

    q: Quat
    """Body FRD → NED; NaN components when the setpoint is body rates."""
    rates: Vec3
    """Body rates [rad/s] for a rate setpoint, or (NaN, NaN, yaw feed-forward) for an attitude setpoint."""
    thrust_body: Vec3
    """Normalised thrust vector in FRD, (0, 0, −collective)."""

    @property
    def is_attitude(self) -> bool:
        return self.q[0] == self.q[0]


_NAN_Q = (math.nan, math.nan, math.nan, math.nan)


def decode_attitude_target(
    msg: mavlink.MAVLink_set_attitude_target_message, previous: OffboardSetpoint | None
) -> OffboardSetpoint | None:
    """The setpoint a SET_ATTITUDE_TARGET carries, or None when it carries none (everything ignored, or a
    quaternion that is not a rotation)."""
    mask = msg.type_mask
    if mask & mavlink.ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE:
        if previous is None:
            return None
        thrust_body = previous.thrust_body
    else:
        if not math.isfinite(msg.thrust):
            return None
        thrust_body = (0.0, 0.0, -min(max(msg.thrust, 0.0), 1.0))
    if not mask & mavlink.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE:
        q = tuple(float(v) for v in msg.q)
        norm = quat.norm(q)
        if not (math.isfinite(norm) and norm > 0.5):
            return None
        yaw_ff = math.nan if mask & mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE else msg.body_yaw_rate
        return OffboardSetpoint(quat.normalized(q), (math.nan, math.nan, yaw_ff), thrust_body)
    if mask & _ALL_RATES_IGNORED == _ALL_RATES_IGNORED:
        return None
    values = (msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate)
    rates = tuple(math.nan if mask & bit else float(v) for bit, v in zip(_RATE_IGNORE, values, strict=True))
    return OffboardSetpoint(_NAN_Q, rates, thrust_body)
