"""Which non-finite values a message may carry, and the first one it should not.

NaN is PX4's "not controlled" in a setpoint or an actuator output: a type that says so
(``Message.NAN_MEANS_NOT_CONTROLLED``) may carry NaN in any float field. A command may carry anything
(``Message.RECEIVER_CHECKS_VALUES``): its receiver judges each value and answers why it refuses one.
Elsewhere (states, sensors, statuses) a float field may carry only what its definition starts with: NaN where
its default is NaN (PX4's "unknown": a sensor's temperature, the local frame's reference before it is set) or
the type names it (``Message.NAN_MEANS_UNKNOWN``: what a source may not report), infinity where its default
is infinite (PX4's "unlimited" or "no accuracy": ``vxy_max``, ``eph``). Any other NaN or infinity is garbage,
and a module never sees it (:class:`stack.runtime.inputs.InputBuffer`): the last good sample stays.

The check runs on every sample a module receives, so the common case is one compiled expression per type (a
sum of the finite-only fields); only a sample that fails it is looked at field by field.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import msgspec
from msgspec import inspect as mi

FINITE, NAN_OK, INF_OK, ANY = 0, 1, 2, 3
"""What a float may be besides finite: nothing, NaN, ±infinity, both."""


@dataclass(frozen=True)
class _Plan:
    names: tuple[str, ...]
    # Per allowance, the fields' positions in ``astuple`` (scalars and fixed tuples apart).
    scalars: dict[int, tuple[int, ...]]
    tuples: dict[int, tuple[int, ...]]
    structs: tuple[int, ...]
    struct_lists: tuple[int, ...]


def _allowance(default: object, not_controlled: bool | None, unknown: bool) -> int:
    if not_controlled is None:
        return ANY
    values = default if isinstance(default, tuple) else (default,)
    nan = not_controlled or unknown or any(isinstance(v, float) and math.isnan(v) for v in values)
    inf = any(isinstance(v, float) and math.isinf(v) for v in values)
    return (NAN_OK if nan else FINITE) | (INF_OK if inf else FINITE)


def _is_floats(t: mi.Type) -> bool:
    if isinstance(t, mi.FloatType):
        return True
    if isinstance(t, mi.TupleType):
        return all(isinstance(item, mi.FloatType) for item in t.item_types)
    return isinstance(t, mi.VarTupleType) and isinstance(t.item_type, mi.FloatType)


@functools.cache
def _plan(cls: type[msgspec.Struct]) -> _Plan:
    not_controlled: bool | None = bool(getattr(cls, "NAN_MEANS_NOT_CONTROLLED", False))
    if getattr(cls, "RECEIVER_CHECKS_VALUES", False):
        not_controlled = None  # any value: the receiver answers for it
    scalars: dict[int, list[int]] = {}
    tuples: dict[int, list[int]] = {}
    structs, struct_lists = [], []
    info = mi.type_info(cls)
    assert isinstance(info, mi.StructType)
    for i, f in enumerate(info.fields):
        t = f.type
        if _is_floats(t):
            default = f.default if f.default is not mi.NODEFAULT else f.default_factory()
            group = scalars if isinstance(t, mi.FloatType) else tuples
            unknown = f.name in getattr(cls, "NAN_MEANS_UNKNOWN", ())
            group.setdefault(_allowance(default, not_controlled, unknown), []).append(i)
        elif isinstance(t, mi.StructType):
            structs.append(i)
        elif isinstance(t, mi.ListType) and isinstance(t.item_type, mi.StructType):
            struct_lists.append(i)
    return _Plan(
        names=tuple(f.name for f in info.fields),
        scalars={k: tuple(v) for k, v in scalars.items()},
        tuples={k: tuple(v) for k, v in tuples.items()},
        structs=tuple(structs),
        struct_lists=tuple(struct_lists),
    )


@functools.cache
def _looks_fine(cls: type[msgspec.Struct]) -> Callable[[Any], bool]:
    """A predicate true when every field of a ``cls`` message is surely allowed, compiled for speed (one sum of
    the finite-only fields, one look for infinity among the NaN-allowed ones); false means look closer."""
    if not issubclass(cls, msgspec.Struct):
        return lambda _: True  # not a message: nothing to judge
    plan = _plan(cls)
    finite, no_inf, no_nan = [], [], []
    for allowed, positions in (*plan.scalars.items(), *plan.tuples.items()):
        for i in positions:
            ref = "*" if i in _tuple_positions(plan) else ""
            term = f"{ref}m.{plan.names[i]}"
            if allowed == FINITE:
                finite.append(f"sum(m.{plan.names[i]})" if ref else term)
            elif allowed == NAN_OK:
                no_inf.append(term)
            elif allowed == INF_OK and ref:
                no_nan.extend(f"m.{plan.names[i]}[{k}]" for k in range(_length(cls, i)))
            elif allowed == INF_OK:
                no_nan.append(term)
    checks = []
    if finite:
        checks.append(f"isfinite({' + '.join(finite)})")
    if no_inf:
        checks.append(f"not (INF in ({', '.join(no_inf)},) or NINF in ({', '.join(no_inf)},))")
    checks.extend(f"{term} == {term}" for term in no_nan)  # NaN is the one value unequal to itself
    if plan.structs or plan.struct_lists:
        checks.append("False")
    source = f"def looks_fine(m):\n    return {' and '.join(checks) or 'True'}\n"
    scope: dict[str, Any] = {"isfinite": math.isfinite, "INF": math.inf, "NINF": -math.inf}
    exec(compile(source, f"<validity of {cls.__name__}>", "exec"), scope)
    return scope["looks_fine"]


def _length(cls: type[msgspec.Struct], i: int) -> int:
    field = msgspec.structs.fields(cls)[i]
    default = field.default if field.default is not msgspec.NODEFAULT else field.default_factory()
    return len(default)


def _tuple_positions(plan: _Plan) -> frozenset[int]:
    return frozenset(i for positions in plan.tuples.values() for i in positions)


def _bad(value: float, allowed: int) -> bool:
    if math.isnan(value):
        return not allowed & NAN_OK
    return math.isinf(value) and not allowed & INF_OK


def _first_bad(values: tuple, plan: _Plan) -> str | None:
    for allowed, positions in plan.scalars.items():
        for i in positions:
            if _bad(values[i], allowed):
                return f"{plan.names[i]} = {values[i]}"
    for allowed, positions in plan.tuples.items():
        for i in positions:
            for k, v in enumerate(values[i]):
                if _bad(v, allowed):
                    return f"{plan.names[i]}[{k}] = {v}"
    for i in plan.structs:
        if (why := refusal(values[i])) is not None:
            return f"{plan.names[i]}.{why}"
    for i in plan.struct_lists:
        for k, item in enumerate(values[i]):
            if (why := refusal(item)) is not None:
                return f"{plan.names[i]}[{k}].{why}"
    return None


_last_fine: list[Any] = [None]


def refusal(msg: Any) -> str | None:
    """The first field of ``msg`` holding a value its type does not allow (``"x = nan"``), or None."""
    # In one process the subscribers of a topic share the message object: it is judged once. The reference
    # kept makes the identity test sound (the object cannot be freed and its address reused meanwhile).
    if msg is _last_fine[0]:
        return None
    if _looks_fine(type(msg))(msg):
        _last_fine[0] = msg
        return None
    return _first_bad(msgspec.structs.astuple(msg), _plan(type(msg)))
