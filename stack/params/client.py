"""The parameters of a running stack, as a ground station sees them: one entry per parameter with its
definition, the modules that read it and their values; get; set in every module that reads it or in
none; reset to the default. ``stack param`` and the MAVLink ground-station link both use these functions.

Each module serves its own parameters (:class:`stack.runtime.services.ParamService`). A set is done in
two phases: every module that holds the parameter first checks the value without changing anything
(``check``), and only when all accept it is it set in each (``set``). If a module still fails to take
it (it stopped meanwhile), the modules already changed are set back, so a set never leaves the modules
disagreeing. The functions block for at most a few Zenoh round trips (``timeout`` each); call them from
a thread of their own where that matters.
"""

from __future__ import annotations

import contextlib
import fnmatch
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import zenoh

from stack.bus import keys
from stack.bus.query import query_json
from stack.names import suggestion
from stack.params.param import Param, ParamError, ParamValue

TIMEOUT_S = 2.0


@dataclass(frozen=True)
class StackParam:
    """One parameter of the running stack: its definition and the value each module that reads it holds."""

    param: Param
    values: Mapping[str, ParamValue]
    """Module name → value, in module-name order."""

    @property
    def name(self) -> str:
        return self.param.name

    @property
    def owners(self) -> tuple[str, ...]:
        return tuple(self.values)

    @property
    def value(self) -> ParamValue:
        """The value (the first module's, should they differ: a profile may give one module its own)."""
        return next(iter(self.values.values()))

    @property
    def consistent(self) -> bool:
        return len(set(self.values.values())) == 1


@dataclass(frozen=True)
class SetResult:
    """A set that every module holding the parameter took: each one's previous value, and the new value."""

    name: str
    old: Mapping[str, ParamValue]
    new: ParamValue


def matches(pattern: str, name: str) -> bool:
    """Shell-style pattern match, case-insensitive (``mc_*p`` matches MC_ROLL_P)."""
    return fnmatch.fnmatchcase(name.upper(), pattern.upper())


def list_params(session: zenoh.Session, vehicle: str, timeout: float = TIMEOUT_S) -> list[StackParam]:
    """Every parameter of every running module of ``vehicle``, by name."""
    definitions: dict[str, Param] = {}
    values: dict[str, dict[str, ParamValue]] = {}
    answers = query_json(session, keys.param_all(vehicle), {"op": "list"}, timeout)
    for answer in sorted(answers, key=lambda a: str(a.get("module", ""))):
        module = str(answer.get("module", ""))
        for d in answer.get("params", []):
            definitions.setdefault(d["name"], Param.from_description(d))
            values.setdefault(d["name"], {})[module] = d["value"]
    return [StackParam(definitions[name], values[name]) for name in sorted(definitions)]


def get_param(session: zenoh.Session, vehicle: str, name: str, timeout: float = TIMEOUT_S) -> StackParam:
    """One parameter, by its name in any case; ParamError (with the closest name) when no module has it."""
    by_name = {p.name: p for p in list_params(session, vehicle, timeout)}
    return by_name[resolve(name, by_name)]


def resolve(name: str, known: Iterable[str]) -> str:
    """``name`` as spelled in ``known`` (case-insensitive), or ParamError suggesting the closest."""
    known = list(known)
    for k in known:
        if k.upper() == name.upper():
            return k
    raise ParamError(f"no running module has a parameter '{name}'{suggestion(name, known)}")


def set_param(
    session: zenoh.Session, vehicle: str, name: str, value: object, timeout: float = TIMEOUT_S
) -> SetResult:
    """Set ``name`` to ``value`` (a number, a bool, or their text) in every module that reads it, or in none:
    raises ParamError with the reason, nothing changed, when any of them refuses it."""
    return set_in_owners(session, vehicle, get_param(session, vehicle, name, timeout), value, timeout)


def reset_param(session: zenoh.Session, vehicle: str, name: str, timeout: float = TIMEOUT_S) -> SetResult:
    """Set ``name`` back to its definition's default (PX4's ``param reset``: the firmware default, not a
    launch profile's or an airframe's value)."""
    p = get_param(session, vehicle, name, timeout)
    return set_in_owners(session, vehicle, p, p.param.default, timeout)


def reset_all(
    session: zenoh.Session, vehicle: str, timeout: float = TIMEOUT_S
) -> tuple[list[SetResult], list[ParamError]]:
    """Every parameter not at its default set back to it: (the sets done, the refusals)."""
    done: list[SetResult] = []
    refused: list[ParamError] = []
    for p in list_params(session, vehicle, timeout):
        if any(v != p.param.default for v in p.values.values()):
            try:
                done.append(set_in_owners(session, vehicle, p, p.param.default, timeout))
            except ParamError as e:
                refused.append(e)
    return done, refused


@dataclass
class LoadReport:
    """What :func:`set_many` did: the sets done, the names already at their value, and one message for each
    value refused or whose name no running module has."""

    changed: list[SetResult]
    unchanged: list[str]
    unknown: list[str]
    refused: list[str]


def set_many(
    session: zenoh.Session,
    vehicle: str,
    values: Iterable[tuple[str, object, int | None]],
    timeout: float = TIMEOUT_S,
) -> LoadReport:
    """Set each ``(name, value, mav_type)``, each atomically as :func:`set_param` does, independently of the
    others (a parameter file's lines). ``mav_type``, when given, must be the parameter's MAV_PARAM_TYPE."""
    by_name = {p.name: p for p in list_params(session, vehicle, timeout)}
    report = LoadReport([], [], [], [])
    for name, value, mav_type in values:
        try:
            p = by_name[resolve(name, by_name)]
        except ParamError as e:
            report.unknown.append(str(e))
            continue
        try:
            if mav_type is not None and mav_type != p.param.mav_type:
                raise ParamError(f"{p.name}: type {mav_type} given, the parameter's is {p.param.mav_type}")
            checked = p.param.check(value)
            if all(v == checked for v in p.values.values()):
                report.unchanged.append(p.name)
                continue
            report.changed.append(set_in_owners(session, vehicle, p, checked, timeout))
        except ParamError as e:
            report.refused.append(str(e))
    return report


def set_in_owners(
    session: zenoh.Session, vehicle: str, p: StackParam, value: object, timeout: float = TIMEOUT_S
) -> SetResult:
    """Set ``p`` to ``value`` in the modules that hold it (``p.owners``): checked by all, then set in all."""
    checked: ParamValue | None = None
    for owner in p.owners:
        reply = _ask(session, vehicle, owner, {"op": "check", "name": p.name, "value": value}, timeout)
        if "error" in reply:
            raise ParamError(f"{reply['error']} (refused by {owner}; nothing changed)")
        checked = reply["value"]
    old: dict[str, ParamValue] = {}
    for owner in p.owners:
        try:
            reply = _ask(session, vehicle, owner, {"op": "set", "name": p.name, "value": checked}, timeout)
            if "error" in reply:
                raise ParamError(f"{reply['error']} (refused by {owner})")
        except ParamError as e:
            _restore(session, vehicle, p.name, old, timeout)
            raise ParamError(f"{e}; the modules already changed were set back") from None
        old[owner] = reply["old"]
    assert checked is not None
    return SetResult(p.name, old, checked)


def _restore(
    session: zenoh.Session, vehicle: str, name: str, old: Mapping[str, ParamValue], timeout: float
) -> None:
    for owner, value in old.items():
        with contextlib.suppress(ParamError):  # that module is gone too: nothing is left to disagree with
            _ask(session, vehicle, owner, {"op": "set", "name": name, "value": value}, timeout)


def _ask(session: zenoh.Session, vehicle: str, module: str, request: dict, timeout: float) -> dict:
    replies = query_json(session, keys.param_key(vehicle, module), request, timeout)
    if not replies:
        raise ParamError(f"{request['name']}: module {module} did not answer")
    return replies[0]
