"""The topic graph as announced by liveliness tokens: who publishes and subscribes to what."""

from __future__ import annotations

from dataclasses import dataclass, field

import zenoh

from stack.bus import keys


@dataclass
class TopicNode:
    topic: str
    instance: int
    type_name: str
    fingerprints: set[str] = field(default_factory=set)
    publishers: list[str] = field(default_factory=list)
    subscribers: list[str] = field(default_factory=list)


def read_graph(session: zenoh.Session, vehicle: str, timeout: float = 1.0) -> dict[tuple[str, int], TopicNode]:
    graph: dict[tuple[str, int], TopicNode] = {}
    for reply in session.liveliness().get(keys.graph_query(vehicle), timeout=timeout):
        if reply.ok is None:
            continue
        # stack/<vehicle>/@graph/<module>/<role>/<topic>/<instance>/<Type>/<fingerprint>
        parts = str(reply.ok.key_expr).split("/")
        if len(parts) != 9:
            continue
        module, role, topic, instance, type_name, fp = parts[3:9]
        node = graph.setdefault((topic, int(instance)), TopicNode(topic, int(instance), type_name))
        node.fingerprints.add(fp)
        (node.publishers if role == "pub" else node.subscribers).append(module)
    for node in graph.values():
        node.publishers.sort()
        node.subscribers.sort()
    return graph
