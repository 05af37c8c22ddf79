"""PX4's attitude setpoints as RotorS roll, pitch, yaw-rate and thrust commands, so that PX4's modes fly on
RotorS' controller (:mod:`stack.attctl.rpyt_control`).

An attitude setpoint R_d (body FRD → NED, from mc_pos_control, Stabilized's sticks or Offboard) is decomposed as
R_d = Rz(ψ_d)·Rx(roll)·Ry(pitch), the form RotorS' controller rebuilds about the current heading. The heading
itself is RotorS' yaw-rate command: yaw_sp_move_rate fed forward plus MC_YAW_P·wrap(ψ_d − ψ), ψ the current
heading in the same decomposition, as PX4's attitude loop turns a yaw error into a yaw rate. A normalised thrust
c (PX4's, thrust_body z = −c) is c × the collective thrust at full command in newtons: with RotorS' quadratic
motors (THR_MDL_FAC = 1) PX4's normalised thrust is linear in the thrust itself.
"""

from __future__ import annotations

import math

from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.attctl.rpyt_control import zxy_angles
from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import wrap_pi
from stack.mathlib.vector import Vec3


def thrust_newtons(thrust_body: Vec3, max_thrust: float) -> float:
    """The collective thrust [N] of a normalised body thrust (z < 0 is up), clipped to [0, ``max_thrust``]; NaN
    when it is not finite, which the controller refuses."""
    collective = -thrust_body[2]
    return min(max(collective, 0.0), 1.0) * max_thrust if math.isfinite(collective) else math.nan


def command_from_attitude(
    q: Quat, q_d: Quat, yaw_sp_move_rate: float, thrust_body: Vec3, yaw_p: float, max_thrust: float
) -> RollPitchYawrateThrust:
    """The RotorS command that holds the attitude setpoint ``q_d`` from the attitude ``q`` (see the module
    docstring); NaN feed-forward is none. A setpoint that is not finite makes a command that is not."""
    yaw_d, roll, pitch = zxy_angles(quat.to_dcm(quat.normalized(q_d)))
    yaw = zxy_angles(quat.to_dcm(quat.normalized(q)))[0]
    feed_forward = yaw_sp_move_rate if math.isfinite(yaw_sp_move_rate) else 0.0
    return RollPitchYawrateThrust(
        roll, pitch, feed_forward + yaw_p * wrap_pi(yaw_d - yaw), thrust_newtons(thrust_body, max_thrust)
    )
