"""The four sticks, as ``manual_control_setpoint`` carries them, and the last setpoint a stick source sends."""

from __future__ import annotations

from typing import NamedTuple

from stack.commander.modes import MODES
from stack.msg.setpoints import ManualControlSetpoint


class Sticks(NamedTuple):
    """Each in [−1, 1]: roll + right, pitch + forward (nose down), yaw + clockwise, throttle −1 minimum."""

    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    throttle: float = -1.0


def setpoint(sticks: Sticks, now_us: int) -> ManualControlSetpoint:
    """The sticks on the bus. A stick source on the ground side, as QGroundControl's joystick reaches PX4 over
    MAVLink: the commander ages it on its own clock from when it arrives."""
    return ManualControlSetpoint(
        timestamp_sample=now_us,
        valid=True,
        data_source=ManualControlSetpoint.SOURCE_MAVLINK_0,
        roll=sticks.roll,
        pitch=sticks.pitch,
        yaw=sticks.yaw,
        throttle=sticks.throttle,
    )


def parting(sticks: Sticks, nav_state: int | None) -> Sticks:
    """The sticks of the last setpoint before the source stops, COM_RC_LOSS_T before the commander's
    manual-control-loss failsafe takes over: roll, pitch and yaw centred; the throttle centred where it is a
    climb rate (Altitude, Position, the automatic modes: centred holds the altitude), and left where it is
    thrust (Stabilized, Acro, RotorS: centred or cut, the vehicle would climb or drop meanwhile)."""
    mode = MODES.get(nav_state) if nav_state is not None else None
    climb_rate = mode is not None and "flag_control_climb_rate_enabled" in mode.control_flags
    return Sticks(throttle=0.0 if climb_rate else sticks.throttle)
