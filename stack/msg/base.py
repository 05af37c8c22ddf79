"""The common base of every uORB-style message and the fixed-size array types fields use.

Messages are msgspec Structs encoded as msgpack arrays (``array_like``): field order is the wire
schema, so fields may only ever be appended, with defaults. Every message starts with
``timestamp`` (µs) like every uORB message.
"""

from __future__ import annotations

import math
from typing import Annotated, ClassVar

import msgspec

NAN = math.nan

F2 = tuple[float, float]
F3 = tuple[float, float, float]
F4 = tuple[float, float, float, float]
F12 = Annotated[tuple[float, ...], msgspec.Meta(min_length=12, max_length=12)]
F16 = Annotated[tuple[float, ...], msgspec.Meta(min_length=16, max_length=16)]
I16 = Annotated[tuple[int, ...], msgspec.Meta(min_length=16, max_length=16)]

ZERO3: F3 = (0.0, 0.0, 0.0)
NAN3: F3 = (NAN, NAN, NAN)
Q_IDENTITY: F4 = (1.0, 0.0, 0.0, 0.0)
ZERO12 = (0.0,) * 12
NAN12 = (NAN,) * 12
ZERO16 = (0.0,) * 16
ZERO16_INT = (0,) * 16


class Message(msgspec.Struct, array_like=True, gc=False):
    """Base of all messages. ``timestamp`` is the publication time in microseconds."""

    timestamp: int = 0

    NAN_MEANS_NOT_CONTROLLED: ClassVar[bool] = False
    """A setpoint, command or output: NaN in any float field is PX4's "not controlled" (stack.msg.validity)."""
    NAN_MEANS_UNKNOWN: ClassVar[frozenset[str]] = frozenset()
    """Fields besides those that start NaN where NaN is "not reported" (a source that does not measure it)."""
    RECEIVER_CHECKS_VALUES: ClassVar[bool] = False
    """A request its receiver judges value by value and answers (a command and its acknowledgement): any float
    reaches it, so that a refusal says why (stack.msg.validity)."""
