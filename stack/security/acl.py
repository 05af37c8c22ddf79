"""The access rules of a host's router, derived from the keystore's identities (Zenoh's ``access_control``).

Everything is denied but what these allow (Zenoh lets a deny win over any allow, so a role's rights are spelled out
as allows, never as exceptions):

- the host's own processes (plain TCP on its loopback interface: its modules, its supervisor, tools run on it) and
  the other hosts of the vehicle (their routers, by the ``host`` identities' names): everything;
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

from pathlib import Path
from typing import Any

from stack.bus import keys
from stack.bus.access import OPEN_TO_TOOLS
from stack.security.keystore import list_identities

EVERY_MESSAGE = (
    "put", "delete", "declare_subscriber", "query", "reply", "declare_queryable", "liveliness_token",
    "liveliness_query", "declare_liveliness_subscriber",
)  # fmt: skip
COMMAND_KEYS = [f"{keys.ROOT}/*/{topic}/*" for topic in sorted(OPEN_TO_TOOLS)]
"""What an operator may publish: what any program that is not a module may (stack.bus.access: commands, sticks,
missions, Offboard setpoints)."""
TOPICS = ["stack/**"]
TOOL_AREAS = keys.area_keys("graph", "alive", "heartbeat", "supervisor", "synced")
"""What a tool reads beyond the topics: the topic graph, who is alive, heartbeats, the supervisors' status."""


def _rule(rule_id: str, flows: list[str], messages: list[str], key_exprs: list[str]) -> dict[str, Any]:
    return {"id": rule_id, "permission": "allow", "flows": flows, "messages": messages, "key_exprs": key_exprs}


def access_rules(keystore: Path) -> dict[str, Any]:
    """Zenoh's ``access_control`` for a host's router of a vehicle whose keystore is ``keystore``."""
    by_role: dict[str, list[str]] = {}
    for identity in list_identities(keystore):
        if not identity.expired():
            by_role.setdefault(identity.role, []).append(identity.name)
    rules = [
        _rule("everything", ["ingress", "egress"], list(EVERY_MESSAGE), ["**", *keys.area_keys()]),
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
        "host": ["everything"],
        "operator": ["read", "receive", "status", "command", "parameters"],
        "observer": ["read", "receive", "status"],
    }
    for role, names in by_role.items():
        if role in rights:
            subjects.append({"id": f"{role}s", "cert_common_names": sorted(names)})
            policies.append({"rules": rights[role], "subjects": [f"{role}s"]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }
