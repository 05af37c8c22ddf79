"""The access rules of a host's router, derived from the keystore's identities (Zenoh's ``access_control``).

Everything is denied but what these allow (Zenoh lets a deny win over any allow, so a role's rights are spelled out
as allows, never as exceptions):

- the host's own processes (plain TCP on its loopback interface: its modules, its supervisor, tools run on it):
  everything;
- another host of the vehicle (its router, by its ``host`` identity's name): everything in the runtime's areas and
  every topic to read, but it may publish only the topics its own modules declare (``Module.PUBLISHES``, where the
  profile places them), what an operator may, and what a flight's script may (``stack fly --host`` runs it on the
  host flying it): a host's certificate cannot publish another host's module's topics. A host identity of the
  keystore that the profile does not name: nothing (a swarm's hubs, which run whole vehicles: everything);
- an ``operator``: publish what a program that is not a module of the profile may (commands, sticks, missions,
  Offboard setpoints: stack.bus.access), ask for parameters (reading and setting them: ``@param`` queries) and
  status (``@supervisor`` queries), and read every topic;
- an ``observer``: read every topic and ask for status;
- any other identity of the keystore, or none: nothing.

Key expressions name the runtime's areas (``@graph``, ``@alive``...) one by one: no wildcard matches an ``@`` chunk,
so ``**`` covers the topics only. Reading a topic takes a subscription (and, for the tools, a token in the topic
graph, so a fast-path run puts the topic on Zenoh for them) going in, and the samples and replies coming out: Zenoh
checks both directions, and a message allowed in but not out toward its reader is lost as surely as one denied. A
denied message is dropped without a word to its sender: the tools check their own role before they send
(stack.cli.common).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from stack.bus import keys
from stack.bus.access import OPEN_TO_TOOLS
from stack.security.keystore import list_identities

EVERY_MESSAGE = (
    "put", "delete", "declare_subscriber", "query", "reply", "declare_queryable", "liveliness_token",
    "liveliness_query", "declare_liveliness_subscriber",
)  # fmt: skip
PUBLISHING = ("put", "delete")
ALL_BUT_PUBLISHING = tuple(m for m in EVERY_MESSAGE if m not in PUBLISHING)


def topic_keys(topics: Iterable[str]) -> list[str]:
    """Key expressions covering ``topics`` of every vehicle, every instance."""
    return [f"{keys.ROOT}/*/{topic}/*" for topic in sorted(topics)]


COMMAND_KEYS = topic_keys(OPEN_TO_TOOLS)
"""What an operator may publish: what any program that is not a module may (stack.bus.access: commands, sticks,
missions, Offboard setpoints)."""
TOPICS = ["stack/**"]
TOOL_AREAS = keys.area_keys("graph", "alive", "heartbeat", "supervisor", "synced")
"""What a tool reads beyond the topics: the topic graph, who is alive, heartbeats, the supervisors' status."""


def _rule(rule_id: str, flows: list[str], messages: list[str], key_exprs: list[str]) -> dict[str, Any]:
    return {"id": rule_id, "permission": "allow", "flows": flows, "messages": messages, "key_exprs": key_exprs}


def flight_topics() -> frozenset[str]:
    """What the script of any flight (``stack fly``) may publish."""
    from stack.runtime.spec import load_module_class
    from stack.scenario.catalogue import scenarios

    scenario = load_module_class("scenario")
    return frozenset().union(*(scenario.publishes({"name": name}) for name in scenarios()))


def access_rules(keystore: Path, hosts: Mapping[str, Iterable[str]] | None = None) -> dict[str, Any]:
    """Zenoh's ``access_control`` for a host's router of a vehicle whose keystore is ``keystore``; ``hosts``: each
    host of the vehicle with the topics its modules publish (None: every host identity may do everything)."""
    by_role: dict[str, list[str]] = {}
    for identity in list_identities(keystore):
        if not identity.expired():
            by_role.setdefault(identity.role, []).append(identity.name)
    rules = [
        _rule("everything", ["ingress", "egress"], list(EVERY_MESSAGE), ["**", *keys.area_keys()]),
        _rule("runtime", ["ingress", "egress"], list(EVERY_MESSAGE), keys.area_keys()),
        _rule("topics", ["egress"], list(EVERY_MESSAGE), ["**"]),
        _rule("topics_but_publishing", ["ingress"], list(ALL_BUT_PUBLISHING), ["**"]),
        _rule("read", ["ingress"], ["declare_subscriber", "liveliness_token", "liveliness_query",
                                    "declare_liveliness_subscriber"], [*TOPICS, *TOOL_AREAS]),
        _rule("receive", ["egress"], ["put", "delete", "reply", "liveliness_token", "declare_subscriber",
                                      "declare_queryable"], [*TOPICS, *TOOL_AREAS, *keys.area_keys("param")]),
        _rule("status", ["ingress"], ["query"], keys.area_keys("supervisor")),
        _rule("command", ["ingress"], ["put"], COMMAND_KEYS),
        _rule("parameters", ["ingress"], ["query"], keys.area_keys("param")),
    ]  # fmt: skip
    subjects: list[dict[str, Any]] = [{"id": "this_host", "interfaces": ["lo"], "link_protocols": ["tcp"]}]
    policies: list[dict[str, Any]] = [{"rules": ["everything"], "subjects": ["this_host"]}]
    rights = {
        "operator": ["read", "receive", "status", "command", "parameters"],
        "observer": ["read", "receive", "status"],
    }
    if hosts is None:
        rights["host"] = ["everything"]
    for role, names in by_role.items():
        if role in rights:
            subjects.append({"id": f"{role}s", "cert_common_names": sorted(names)})
            policies.append({"rules": rights[role], "subjects": [f"{role}s"]})
    if hosts is not None:
        beyond_modules = OPEN_TO_TOOLS | flight_topics()
        for host in sorted(set(hosts) & set(by_role.get("host", ()))):
            own = topic_keys({*hosts[host], *beyond_modules})
            rules.append(_rule(f"publish_{host}", ["ingress"], list(PUBLISHING), own))
            subjects.append({"id": f"host_{host}", "cert_common_names": [host]})
            rights_of_host = ["runtime", "topics", "topics_but_publishing", f"publish_{host}"]
            policies.append({"rules": rights_of_host, "subjects": [f"host_{host}"]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }
