"""Zenoh key layout.

Flight topics:      ``stack/<vehicle>/<topic>/<instance>``
Runtime internals:  ``stack/<vehicle>/@<area>/...`` — Zenoh never matches an ``@`` chunk with a
wildcard, so ``stack/<vehicle>/**`` (what a recorder or a bridge subscribes to) sees topics only.

The graph lives in liveliness tokens, so listing topics needs no central registry:
``stack/<vehicle>/@graph/<module>/<pub|sub>/<topic>/<instance>/<Type>/<fingerprint>``.
"""

from __future__ import annotations

import re

ROOT = "stack"
AREAS = ("alive", "graph", "heartbeat", "lockstep", "param", "scenario", "supervisor", "synced", "world")
"""The runtime's areas of a vehicle's keys (``stack/<vehicle>/@<area>/...``): a key expression names each one it
covers, since no wildcard matches an ``@`` chunk (the access rules list them, stack.security.acl)."""


def area_keys(*areas: str) -> list[str]:
    """Key expressions covering every vehicle's ``areas`` (all of them when none is named)."""
    return [f"{ROOT}/*/@{area}/**" for area in areas or AREAS]
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_\-]*$")


def valid_name(name: str) -> bool:
    """Names become key chunks: letters, digits, '_' and '-' only."""
    return _NAME.match(name) is not None


def check_name(kind: str, name: str) -> str:
    """``name`` if :func:`valid_name`, else a ValueError saying why."""
    if not valid_name(name):
        raise ValueError(f"invalid {kind} name '{name}': use letters, digits, '_' and '-' only")
    return name


def vehicle_root(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}"


def topic_key(vehicle: str, topic: str, instance: int = 0) -> str:
    return f"{ROOT}/{vehicle}/{topic}/{instance}"


def topic_suffix(topic: str, instance: int = 0) -> str:
    """The per-vehicle part of a topic key, used to name topics inside the lockstep protocol."""
    return f"{topic}/{instance}"


def all_topics(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/*/*"


def parse_topic_key(key: str) -> tuple[str, str, int] | None:
    """``stack/<vehicle>/<topic>/<instance>`` → (vehicle, topic, instance), or None."""
    parts = key.split("/")
    if len(parts) != 4 or parts[0] != ROOT or parts[2].startswith("@"):
        return None
    try:
        return parts[1], parts[2], int(parts[3])
    except ValueError:
        return None


def graph_token(vehicle: str, module: str, role: str, topic: str, instance: int, type_name: str, fp: int) -> str:
    return f"{ROOT}/{vehicle}/@graph/{module}/{role}/{topic}/{instance}/{type_name}/{fp:016x}"


def graph_query(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@graph/**"


def alive_token(vehicle: str, module: str, pid: int) -> str:
    return f"{ROOT}/{vehicle}/@alive/{module}/{pid}"


def alive_query(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@alive/**"


def heartbeat_key(vehicle: str, module: str) -> str:
    return f"{ROOT}/{vehicle}/@heartbeat/{module}"


def heartbeat_all(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@heartbeat/*"


def param_key(vehicle: str, module: str) -> str:
    return f"{ROOT}/{vehicle}/@param/{module}"


def param_all(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@param/*"


def lockstep_clock_key(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@lockstep/clock"


def lockstep_tick_key(vehicle: str, member: str) -> str:
    """Where a timed lockstep member receives the clock, only on the steps its timer is due."""
    return f"{ROOT}/{vehicle}/@lockstep/tick/{member}"


def lockstep_ack_key(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@lockstep/ack"


def lockstep_member_token(vehicle: str, member: str, publisher_id: int, trigger: str) -> str:
    """``trigger`` is ``topic/<name>/<instance>`` or ``timer/<period_us>``."""
    return f"{ROOT}/{vehicle}/@lockstep/member/{member}/{publisher_id}/{trigger}"


def lockstep_member_query(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@lockstep/member/**"


def synced_token(vehicle: str, module: str) -> str:
    return f"{ROOT}/{vehicle}/@synced/{module}"


def synced_query(vehicle: str) -> str:
    return f"{ROOT}/{vehicle}/@synced/*"


def scenario_result_key(vehicle: str) -> str:
    """Where a vehicle's scenario puts its result as it ends (the launchers of a swarm flight read it)."""
    return f"{ROOT}/{vehicle}/@scenario/result"


def supervisor_key(vehicle: str, host: str, what: str) -> str:
    """What the supervisor of one host of the vehicle answers (its roster, status...)."""
    return f"{ROOT}/{vehicle}/@supervisor/{host}/{what}"


def supervisor_query(vehicle: str, what: str) -> str:
    """The same of every host's supervisor."""
    return f"{ROOT}/{vehicle}/@supervisor/*/{what}"
