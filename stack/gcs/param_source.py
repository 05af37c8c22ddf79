"""The stack's parameters as a :class:`~stack.gcs.params.ParamSource`, over the modules' parameter services.

Each module answers JSON queries on ``keys.param_key(vehicle, module)`` (``stack.runtime.services.ParamService``,
what ``stack param`` uses). A parameter several modules declare is listed once (the first module's value, by
module name) and set in every module that has it; if one refuses, those already changed are set back and the
first refusal's reason is raised, so the change is all or nothing. String parameters are not listed.
"""

from __future__ import annotations

import zenoh

from stack.bus import keys
from stack.cli.common import query_json
from stack.gcs.params import ParamNumber
from stack.runtime.params import ParamError

INTEGER_TYPES = ("int", "bool")
NUMERIC_TYPES = (*INTEGER_TYPES, "float")


class BusParamSource:
    def __init__(self, session: zenoh.Session, vehicle: str, timeout_s: float = 2.0) -> None:
        self.session = session
        self.vehicle = vehicle
        self.timeout_s = timeout_s

    def _answers(self, request: dict[str, object]) -> list[dict]:
        answers = query_json(self.session, keys.param_all(self.vehicle), request, self.timeout_s)
        return sorted(answers, key=lambda a: str(a.get("module", "")))

    def list(self) -> list[tuple[str, ParamNumber, bool]]:
        seen: dict[str, tuple[str, ParamNumber, bool]] = {}
        for answer in self._answers({"op": "list"}):
            for p in answer.get("params", []):
                if p.get("type") in NUMERIC_TYPES and p["name"] not in seen:
                    is_int = p["type"] in INTEGER_TYPES
                    seen[p["name"]] = (p["name"], int(p["value"]) if is_int else float(p["value"]), is_int)
        return list(seen.values())

    def set(self, name: str, value: ParamNumber) -> ParamNumber:
        owners = [a["module"] for a in self._answers({"op": "get", "name": name}) if "error" not in a]
        if not owners:
            raise ParamError(f"no running module has a parameter '{name}'")
        done: list[tuple[str, object]] = []
        new: object = value
        for owner in owners:
            replies = query_json(
                self.session,
                keys.param_key(self.vehicle, owner),
                {"op": "set", "name": name, "value": value},
                self.timeout_s,
            )
            reply = replies[0] if replies else {"error": f"{owner} did not answer"}
            if "error" in reply:
                for module, old in done:
                    query_json(
                        self.session, keys.param_key(self.vehicle, module), {"op": "set", "name": name, "value": old}
                    )
                raise ParamError(str(reply["error"]).removeprefix(f"{name}: "))
            done.append((owner, reply["old"]))
            new = reply["new"]
        return int(new) if isinstance(new, bool | int) else float(new)  # type: ignore[arg-type]
