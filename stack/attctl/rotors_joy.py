"""The sticks of the RotorS mode, mapped as RotorS' joystick interface maps a gamepad.

``rotors_joy_interface/src/joy.cpp`` (ethz-asl/rotors_simulator) turns ROS joystick axes into a
``mav_msgs/RollPitchYawrateThrust`` command: roll = −axis0·max_roll, pitch = axis1·max_pitch, yaw rate ±max_yaw_rate
while one of two buttons is held, thrust = (axis2 + 1)·max_thrust/2. ROS axes are positive left and forward and the
command is in body FLU, so in ``manual_control_setpoint`` terms (roll + right, pitch + forward = nose down, yaw +
clockwise, throttle −1..1) and the stack's FRD command that is roll = roll_stick·max_roll, pitch =
−pitch_stick·max_pitch, yaw rate = yaw_stick·max_yaw_rate (the stick in place of joy.cpp's two buttons: full
deflection is the button) and thrust = (throttle + 1)·max_thrust/2.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.params.binding import ParamSet
from stack.params.param import Param


class RotorsJoyParams(ParamSet):
    """The joystick mapping's full-stick angles, yaw rate and thrust (the catalogue's RJOY_*)."""

    rjoy_roll_max: float
    rjoy_pitch_max: float
    rjoy_yawrate_max: float
    rjoy_thr_max: float


PARAMS: tuple[Param, ...] = RotorsJoyParams.PARAMS


class RollPitchYawrateThrust(NamedTuple):
    """A RotorS command in the stack's frames: roll, pitch [rad] (FRD, pitch + nose up), yaw rate [rad/s,
    clockwise +], collective thrust [N]."""

    roll: float
    pitch: float
    yaw_rate: float
    thrust: float


def _clip(stick: float) -> float:
    return min(max(stick, -1.0), 1.0) if math.isfinite(stick) else 0.0


class JoyMapping:
    """joy.cpp's stick scaling; a non-finite stick reads as centred (throttle: minimum)."""

    __slots__ = ("_pitch_max", "_roll_max", "_thrust_max", "_yaw_rate_max")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = RotorsJoyParams.from_params(params)
        self._roll_max = math.radians(p.rjoy_roll_max)
        self._pitch_max = math.radians(p.rjoy_pitch_max)
        self._yaw_rate_max = math.radians(p.rjoy_yawrate_max)
        self._thrust_max = p.rjoy_thr_max

    def command(self, roll: float, pitch: float, yaw: float, throttle: float) -> RollPitchYawrateThrust:
        throttle = _clip(throttle) if math.isfinite(throttle) else -1.0
        return RollPitchYawrateThrust(
            roll=_clip(roll) * self._roll_max,
            pitch=-_clip(pitch) * self._pitch_max,
            yaw_rate=_clip(yaw) * self._yaw_rate_max,
            thrust=(throttle + 1.0) * 0.5 * self._thrust_max,
        )
