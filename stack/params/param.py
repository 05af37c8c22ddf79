"""A parameter's definition, after PX4's parameter metadata: type, default, range, unit, description and,
for an enum or a bitmask, what each value or bit means.

On MAVLink (PARAM_VALUE, QGroundControl's ``.params`` files) PX4 has only two types: INT32 and REAL32. A
``bool`` or an enum parameter is INT32 there, a ``float`` REAL32. A parameter is never a string: MAVLink
cannot carry one, so a definition with any other type is refused.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, cast

ParamValue = bool | int | float | str
"""A parameter's or a launch argument's value (arguments may be strings, parameters may not)."""

MAV_PARAM_TYPE_INT32 = 6
MAV_PARAM_TYPE_REAL32 = 9

ENABLED: dict[int, str] = {0: "Disabled", 1: "Enabled"}
"""The values of a PX4 ``@boolean`` parameter that the stack keeps as an integer."""


class ParamError(ValueError):
    """A parameter name or value was rejected; the message says why."""


def convert(name: str, kind: type, value: object) -> ParamValue:
    """``value`` as a ``kind`` (bool, int, float or str): a number, or its text as given on a command line or in
    a file. Raises ParamError naming ``name`` when it is not one."""
    if kind is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, int) and value in (0, 1):
            return bool(value)
        if isinstance(value, str) and value.lower() in ("true", "false", "1", "0"):
            return value.lower() in ("true", "1")
        raise ParamError(f"{name}: expected a boolean, got {value!r}")
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int | str | float):
            raise ParamError(f"{name}: expected an integer, got {value!r}")
        if isinstance(value, float):
            if not value.is_integer():
                raise ParamError(f"{name}: expected an integer, got {value!r}")
            return int(value)
        try:
            return int(value)
        except ValueError:
            raise ParamError(f"{name}: expected an integer, got {value!r}") from None
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise ParamError(f"{name}: expected a number, got {value!r}")
        try:
            v = float(value)
        except ValueError:
            raise ParamError(f"{name}: expected a number, got {value!r}") from None
        if not math.isfinite(v):
            raise ParamError(f"{name}: {value!r} is not a finite number")
        return v
    if not isinstance(value, str):
        raise ParamError(f"{name}: expected a string, got {value!r}")
    return value


@dataclass(frozen=True)
class Param:
    """One parameter. ``values`` makes it an enum: only those values are accepted, each with its meaning.
    ``bits`` makes it a bitmask: bit number → meaning; only those bits may be set."""

    name: str
    default: bool | int | float
    min: float | None = None
    max: float | None = None
    unit: str = ""
    doc: str = ""
    values: Mapping[int, str] = field(default_factory=dict, hash=False)
    bits: Mapping[int, str] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        if type(self.default) not in (bool, int, float):
            raise TypeError(f"{self.name}: a parameter is a bool, an int or a float (MAVLink has no other)")
        if (self.values or self.bits) and type(self.default) is not int:
            raise TypeError(f"{self.name}: only an int parameter has enum values or bits")

    @property
    def type(self) -> type:
        return type(self.default)

    @property
    def mav_type(self) -> int:
        """MAV_PARAM_TYPE on MAVLink: REAL32 for a float, INT32 for anything else (bool, int, enum)."""
        return MAV_PARAM_TYPE_REAL32 if self.type is float else MAV_PARAM_TYPE_INT32

    def check(self, value: object) -> bool | int | float:
        """Return ``value`` converted to this parameter's type, or raise ParamError with the reason."""
        v = cast(bool | int | float, convert(self.name, self.type, value))
        if self.values and v not in self.values:
            allowed = ", ".join(f"{k} ({m})" for k, m in self.values.items())
            raise ParamError(f"{self.name}: {v!r} is not one of {allowed}")
        if self.bits and (v < 0 or v & ~sum(1 << b for b in self.bits)):
            allowed = ", ".join(f"{b} ({m})" for b, m in self.bits.items())
            raise ParamError(f"{self.name}: {v!r} sets a bit other than {allowed}")
        if not isinstance(v, bool):
            allowed = f" (range {self.min:g} to {self.max:g})" if self.min is not None and self.max is not None else ""
            if self.min is not None and v < self.min:
                raise ParamError(f"{self.name}: {v!r} is below the minimum {self.min:g}{allowed}")
            if self.max is not None and v > self.max:
                raise ParamError(f"{self.name}: {v!r} is above the maximum {self.max:g}{allowed}")
        return v

    def meaning(self, value: object) -> str:
        """What ``value`` means for an enum ("Return mode") or a bitmask ("Mission + Auto modes"); else ""."""
        if isinstance(value, bool) or not isinstance(value, int):
            return ""
        if self.values:
            return self.values.get(value, "")
        if self.bits:
            return " + ".join(m for b, m in self.bits.items() if value & (1 << b)) or "none"
        return ""

    def describe(self) -> dict[str, object]:
        """The definition as JSON-ready data (the parameter service's ``list`` reply)."""
        return {
            "name": self.name,
            "type": self.type.__name__,
            "mav_type": self.mav_type,
            "default": self.default,
            "min": self.min,
            "max": self.max,
            "unit": self.unit,
            "doc": self.doc,
            "choices": list(self.values),
            "values": [[v, m] for v, m in self.values.items()],
            "bits": [[b, m] for b, m in self.bits.items()],
        }

    @classmethod
    def from_description(cls, d: Mapping[str, Any]) -> Param:
        """The definition back from :meth:`describe` (what a running module reports)."""
        kind = {"bool": bool, "int": int, "float": float}.get(str(d.get("type")))
        if kind is None:
            raise ParamError(f"{d.get('name')}: unknown parameter type {d.get('type')!r}")
        return cls(
            name=str(d["name"]),
            default=kind(d["default"]),
            min=d.get("min"),
            max=d.get("max"),
            unit=str(d.get("unit", "")),
            doc=str(d.get("doc", "")),
            values={int(v): str(m) for v, m in d.get("values") or ()},
            bits={int(b): str(m) for b, m in d.get("bits") or ()},
        )
