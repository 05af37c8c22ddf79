"""MANUAL_CONTROL (QGroundControl's virtual joystick, MAVSDK's manual control) → ``manual_control_setpoint``.

As PX4's receiver (``MavlinkReceiver::handle_message_manual_control``): x is pitch (forward = nose down), y roll,
r yaw, each −1000..1000 to −1..1; z is throttle 0..1000 to −1..1; the message must name this system. A value out
of its range is refused, nothing published. The commander counts the stick input lost COM_RC_LOSS_T after the
last valid ``manual_control_setpoint``, or at once when one says it is invalid, and takes its NAV_RCL_ACT action.
:class:`ManualInput` repeats the last sticks, stamped with the stack's time, every REPUBLISH_US of wall time while
the ground station keeps sending them (in lockstep the simulation runs ~10× faster than the wall, so a 20 Hz
joystick would otherwise look 0.5 s apart), and publishes them once more with ``valid`` false when they have not
come for LOSS_US of wall time.
"""

from __future__ import annotations

from typing import Any

from stack.mavlink.offboard import REPUBLISH_US
from stack.msg.setpoints import ManualControlSetpoint
from stack.params import catalogue

AXIS_RANGE = 1000
LOSS_US = round(catalogue.get("COM_RC_LOSS_T").default * 1e6)


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
    """The last sticks and when they came (wall clock): repeated while they keep coming, invalid once when they stop."""

    def __init__(self) -> None:
        self.last: ManualControlSetpoint | None = None
        self._received_us = 0
        self._sent_us = 0

    def on_sticks(self, sticks: ManualControlSetpoint, now_wall_us: int) -> None:
        self.last = sticks
        self._received_us = self._sent_us = now_wall_us

    def due(self, now_wall_us: int, stamp_us: int) -> ManualControlSetpoint | None:
        """The setpoint to publish now, stamped ``stamp_us``: the last sticks again, or the invalid setpoint when the
        input has just been lost; None when nothing is due."""
        last = self.last
        if last is None:
            return None
        if now_wall_us - self._received_us > LOSS_US:
            self.last = None
            last.valid = False
        elif now_wall_us - self._sent_us < REPUBLISH_US:
            return None
        self._sent_us = now_wall_us
        last.timestamp = stamp_us
        return last
