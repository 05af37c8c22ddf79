"""Control allocation and outputs (PX4 ``ActuatorMotors``, ``ActuatorOutputs``, ``ControlAllocatorStatus``)."""

from __future__ import annotations

from stack.msg.base import F3, F12, F16, I16, NAN12, ZERO3, ZERO16, ZERO16_INT, Message

MOTOR_SLOTS = 12
"""Motors an ``ActuatorMotors`` carries (PX4 ``actuator_motors.msg`` NUM_CONTROLS)."""
OUTPUT_SLOTS = 16
"""Outputs an ``ActuatorOutputs`` carries (PX4 ``actuator_outputs.msg`` NUM_ACTUATOR_OUTPUTS)."""


def pad(values: tuple[float, ...], size: int, fill: float) -> tuple[float, ...]:
    """``values`` cut or filled with ``fill`` to ``size``: a message's fixed-length array."""
    return values[:size] + (fill,) * (size - len(values))


class ActuatorMotors(Message):
    """Motor commands in [−1, 1] (non-reversible motors use [0, 1]); NaN means stopped/disarmed."""

    NAN_MEANS_NOT_CONTROLLED = True

    timestamp_sample: int = 0
    reversible_flags: int = 0
    control: F12 = NAN12


class ActuatorOutputs(Message):
    """Output values in natural units: PWM µs on ``actuator_outputs``, [0, 1] on ``actuator_outputs_sim``."""

    NAN_MEANS_NOT_CONTROLLED = True

    noutputs: int = 0
    output: F16 = ZERO16


class ControlAllocatorStatus(Message):
    """How well the allocator met the setpoint; the rate loop uses the unallocated torque signs."""

    SATURATION_OK = 0
    SATURATION_UPPER_DYN = 1
    SATURATION_UPPER = 2
    SATURATION_LOWER_DYN = -1
    SATURATION_LOWER = -2

    torque_setpoint_achieved: bool = True
    unallocated_torque: F3 = ZERO3
    thrust_setpoint_achieved: bool = True
    unallocated_thrust: F3 = ZERO3
    actuator_saturation: I16 = ZERO16_INT
    handled_motor_failure_mask: int = 0
    motor_stop_mask: int = 0
