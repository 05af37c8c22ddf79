"""MANUAL_CONTROL (QGroundControl's virtual joystick, MAVSDK's manual control) → ``manual_control_setpoint``.

As PX4's receiver (``MavlinkReceiver::handle_message_manual_control``): x is pitch (forward = nose down), y roll,
r yaw, each −1000..1000 to −1..1; z is throttle 0..1000 to −1..1; the message must name this system. A value out
of its range is refused, nothing published. PX4 counts the stick input lost after COM_RC_LOSS_T (0.5 s by
default) without a message: :class:`ManualInput` then publishes the last sticks once more with ``valid`` false.
The stack's commander has no RC-loss failsafe to act on it.
"""

from __future__ import annotations

from typing import Any

from stack.msg.setpoints import ManualControlSetpoint

AXIS_RANGE = 1000
LOSS_US = 500_000
"""PX4 COM_RC_LOSS_T's default."""


class Refused(ValueError):
    pass


def manual_control(msg: Any, now_us: int) -> ManualControlSetpoint:
    for name in ("x", "y", "r"):
        value = getattr(msg, name)
        if not -AXIS_RANGE <= value <= AXIS_RANGE:
            raise Refused(f"MANUAL_CONTROL {name} = {value} is outside ±{AXIS_RANGE}")
    if not 0 <= msg.z <= AXIS_RANGE:
        raise Refused(f"MANUAL_CONTROL z = {msg.z} is outside 0..{AXIS_RANGE}")
    return ManualControlSetpoint(
        timestamp=now_us,
        timestamp_sample=now_us,
        valid=True,
        data_source=ManualControlSetpoint.SOURCE_MAVLINK_0,
        roll=msg.y / AXIS_RANGE,
        pitch=msg.x / AXIS_RANGE,
        yaw=msg.r / AXIS_RANGE,
        throttle=msg.z / AXIS_RANGE * 2.0 - 1.0,
        buttons=msg.buttons,
    )


class ManualInput:
    """The last sticks and when they came (wall clock); ``lost`` once when they stop."""

    def __init__(self) -> None:
        self.last: ManualControlSetpoint | None = None
        self._received_us = 0

    def on_sticks(self, sticks: ManualControlSetpoint, now_wall_us: int) -> None:
        self.last = sticks
        self._received_us = now_wall_us

    def lost(self, now_wall_us: int, stamp_us: int) -> ManualControlSetpoint | None:
        """The invalid setpoint to publish when the input has just been lost, else None."""
        if self.last is None or now_wall_us - self._received_us <= LOSS_US:
            return None
        last, self.last = self.last, None
        last.valid = False
        last.timestamp = stamp_us
        return last
