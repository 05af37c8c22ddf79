"""Who a module hears: on each topic, the profile's modules that declare they publish it; anyone else only on the
topics open to tools.

A vehicle's topics are published by the modules its profile starts, each on the topics its class declares
(``Module.PUBLISHES``). Programs that are not modules of the
profile (``stack cmd``, ``stack teleop``, ``stack topic pub``, a user's script on the bus) may publish what
PX4 lets a ground station or an offboard computer send: commands, sticks, missions, and the Offboard
setpoints (PX4's ROS 2 offboard topics, ``docs/en/ros2/offboard_control.md``), the last heard from them only
while the vehicle is in Offboard, so a stray publisher cannot displace the setpoint the flight modes publish.
A profile may open more topics (``[stack] open_topics``: a test that feeds a module by hand).

A sample from anyone else, a module of the profile included, is counted as ``unauthorized`` by the module that
receives it and never seen. The
publisher is told by the id in the stack's message header (:mod:`stack.bus.topics`), which a process that
wants to lie can forge: this guards against mistakes and stray processes on the vehicle's own bus, not a
hostile host, which Zenoh's certificates and access control keep off the bus.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from stack.bus.node import stable_publisher_id
from stack.msg.registry import TOPICS
from stack.msg.topic import FromTools

OPEN_TO_TOOLS = frozenset(name for name, topic in TOPICS.items() if topic.from_tools is not FromTools.NEVER)
"""The topics a program that is not a module of the profile may publish (each topic's ``from_tools``)."""


NOBODY: frozenset[int] = frozenset()


@dataclass(frozen=True)
class Access:
    """The publishers a module of ``vehicle`` hears: on each topic, the profile's modules declaring it (``publishers``,
    by publisher id) and, on ``open_topics`` (beyond :data:`OPEN_TO_TOOLS`), anyone."""

    publishers: Mapping[str, frozenset[int]]
    open_topics: frozenset[str] = frozenset()

    @staticmethod
    def of(vehicle: str, modules: Mapping[str, Iterable[str]], open_topics: Iterable[str] = ()) -> Access:
        """``modules``: each module of the profile by name, with the topics it publishes."""
        ids: dict[str, set[int]] = {}
        for module, topics in modules.items():
            for topic in topics:
                ids.setdefault(topic, set()).add(stable_publisher_id(vehicle, module))
        return Access({topic: frozenset(found) for topic, found in ids.items()}, frozenset(open_topics))

    def publishers_of(self, topic: str) -> frozenset[int]:
        """The modules that may publish ``topic`` (by publisher id); none for a topic no module declares."""
        return self.publishers.get(topic, NOBODY)

    def rule(self, topic: str) -> str:
        """How a topic is heard: ``members`` only, ``anyone``, or ``offboard`` (anyone while in Offboard)."""
        if topic in self.open_topics:
            return FromTools.ALWAYS.value
        known = TOPICS.get(topic)
        return FromTools.NEVER.value if known is None else known.from_tools.value


def tool_may_publish(topic: str, open_topics: Iterable[str] = ()) -> bool:
    """Whether a program that is not a module of the profile may publish ``topic``."""
    return topic in OPEN_TO_TOOLS or topic in set(open_topics)
