"""What the vehicle's supervisors answer, one per host, taken together.

A vehicle spread over several machines has one supervisor on each (``stack up PROFILE --host NAME``), each
answering for the modules of its host. The roster lockstep waits for is the vehicle's: complete once every
host that runs modules has started all of its own, in the same run. ``stack status`` and the tools see one
vehicle: the status rows of every host, each naming its host.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence

import zenoh

from stack.bus import keys
from stack.bus.query import query_json

ROSTER_TIMEOUT_S = 1.0
SINGLE_HOST = "local"
"""The host of a vehicle on one machine (a profile without ``[hosts]``): its supervisor answers under this name."""


def rosters(session: zenoh.Session, vehicle: str, timeout: float = ROSTER_TIMEOUT_S) -> list[dict]:
    """Each answering supervisor's roster: ``{"host", "leads", "run_id", "complete", "modules": {name: pid}, "seed",
    "params": {module: {name: value}}, "publishes": {module: [topic]}}`` (``leads``: its host runs the lockstep's
    coordinator and gave the run its id; its seed and parameters are the run's; ``publishes``: what each module of
    the vehicle publishes, as far as that host knows)."""
    out = []
    for reply in session.get(
        keys.supervisor_query(vehicle, "roster"),
        consolidation=zenoh.ConsolidationMode.NONE,
        target=zenoh.QueryTarget.ALL,
        timeout=timeout,
    ):
        if reply.ok is None:
            continue
        try:
            data = json.loads(reply.ok.payload.to_string())
            out.append(
                {
                    "host": str(data["host"]),
                    "leads": bool(data["leads"]),
                    "run_id": int(data["run_id"]),
                    "complete": bool(data["complete"]),
                    "modules": {str(k): int(v) for k, v in data["modules"].items()},
                    "seed": int(data["seed"]),
                    "params": {str(m): dict(p) for m, p in data["params"].items()},
                    "publishes": {str(m): [str(t) for t in topics] for m, topics in data["publishes"].items()},
                }
            )
        except (ValueError, KeyError, TypeError, AttributeError):
            continue
    return out


def complete_roster(answers: Iterable[dict], hosts: Sequence[str], run_id: int) -> dict[str, int] | None:
    """The vehicle's modules (name → pid) once the supervisor of every one of ``hosts`` has answered, complete, for
    the run ``run_id`` (a supervisor of another run, still up or stale, is not this vehicle's); else None."""
    complete = {a["host"]: a["modules"] for a in answers if a["run_id"] == run_id and a["complete"]}
    if not all(h in complete for h in hosts):
        return None
    return {name: pid for h in hosts for name, pid in complete[h].items()}


def vehicle_status(session: zenoh.Session, vehicle: str, timeout: float = 2.0) -> dict | None:
    """Every host's status as one: the first answer's vehicle facts, and every host's module rows in host order
    (each row names its host); None when no supervisor answers. ``silent_hosts``: the hosts of the profile that run
    modules and did not answer (``placement`` says which modules are theirs); ``lost_hosts``: host → the answering
    hosts that count it lost (stack.bus.host_beats); ``denied``: host → what its router's access rules refused
    (stack.security.denials), for the hosts whose router refused anything."""
    answers = query_json(session, keys.supervisor_query(vehicle, "status"), timeout=timeout)
    return merged_status(answers) if answers else None


def vehicles_status(session: zenoh.Session, timeout: float = 2.0) -> dict[str, dict]:
    """Every vehicle whose supervisors answer on the bus: vehicle → its status as :func:`vehicle_status` gives it."""
    by_vehicle: dict[str, list[dict]] = {}
    for answer in query_json(session, keys.supervisor_query("*", "status"), timeout=timeout):
        if isinstance(answer, dict) and isinstance(answer.get("vehicle"), str):
            by_vehicle.setdefault(answer["vehicle"], []).append(answer)
    return {vehicle: merged_status(answers) for vehicle, answers in sorted(by_vehicle.items())}


def merged_status(answers: list[dict]) -> dict:
    """One vehicle's status from its supervisors' answers (see :func:`vehicle_status`)."""
    answers.sort(key=lambda a: (a.get("host_order", 0), str(a.get("host", ""))))
    report = dict(answers[0])
    report["modules"] = [row for a in answers for row in a.get("modules", [])]
    report["hosts"] = [a.get("host", "") for a in answers]
    placement: dict[str, list[str]] = report.get("placement", {})
    report["silent_hosts"] = [h for h, names in placement.items() if names and h not in report["hosts"]]
    lost: dict[str, list[str]] = {}
    for a in answers:
        for h in a.get("lost_hosts", []):
            lost.setdefault(str(h), []).append(str(a.get("host", "")))
    report["lost_hosts"] = lost
    report["denied"] = {str(a.get("host", "")): a["denied"] for a in answers if a.get("denied")}
    return report


def module_states(session: zenoh.Session, vehicle: str) -> dict[str, str]:
    """Module name → state, from every host's supervisor."""
    report = vehicle_status(session, vehicle, timeout=1.0)
    if report is None:
        return {}
    try:
        return {str(r["module"]): str(r["state"]) for r in report["modules"]}
    except (KeyError, TypeError):
        return {}


def outside_ready(session: zenoh.Session, vehicle: str, wanted: set[str]) -> bool:
    """Whether every host's fast path puts the ``topic/instance`` in ``wanted`` on Zenoh (a host without a fast
    path puts every topic there)."""
    answers = query_json(session, keys.supervisor_query(vehicle, "outside"))
    return all(not a.get("fast_path") or wanted <= set(a.get("topics", ())) for a in answers)
