"""A topic's handle, as PX4's ``ORB_ID``: its name, its message type and what the runtime must know of it.

Modules subscribe and publish by handle (``self.latest(ORB_ID.vehicle_attitude)`` is a ``VehicleAttitude``);
the topic's name, a string, is used only where it meets the outside: Zenoh keys, recordings and the CLI.
"""

from __future__ import annotations

from enum import Enum
from typing import Generic, TypeVar

from stack.msg.base import Message

M = TypeVar("M", bound=Message)


class FromTools(Enum):
    """Whether a program that is not a module of the profile (a ground station, ``stack cmd``, an offboard
    script) may publish the topic, as PX4 takes it from a ground station or an offboard computer."""

    NEVER = "members"
    """Only the profile's own modules are heard."""
    ALWAYS = "anyone"
    """Anyone, in any mode: commands, sticks, missions (a ground station's COMMAND_LONG, RC, mission upload)."""
    IN_OFFBOARD = "offboard"
    """Anyone, but heard only while the vehicle flies Offboard (PX4's offboard setpoints,
    ``docs/en/ros2/offboard_control.md``), so a stray publisher cannot displace the flight modes' setpoint."""


class Topic(Generic[M]):
    """One topic of the catalogue; its name is the attribute that holds it (see :class:`stack.msg.registry.ORB_ID`)."""

    __slots__ = ("from_tools", "name", "telemetry", "type")

    def __init__(self, type_: type[M], *, telemetry: bool = False, from_tools: FromTools = FromTools.NEVER) -> None:
        self.type = type_
        self.name = ""
        self.telemetry = telemetry
        """A diagnostic nothing in the control path reads: in real time it may be dropped under load rather than
        stall its publisher (everything else, commands and state, is sent reliably)."""
        self.from_tools = from_tools

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return f"ORB_ID.{self.name}"


def topic_name(topic: Topic) -> str:
    """The name of a handle; anything else (a topic named by a string) is refused with the rule."""
    if not isinstance(topic, Topic):
        raise TypeError(f"a topic is named by its handle (stack.msg.registry.ORB_ID), not {topic!r}")
    return topic.name
