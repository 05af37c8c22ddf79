"""PX4-style parameters: named, typed, with defaults and ranges, changeable while a module runs.

A module declares its parameters; a launch profile may override them; ``stack param set`` changes
them at run time. Changes arrive on the parameter service's thread and are applied by the module's
own loop between runs, so an algorithm never sees a half-applied update.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

ParamValue = bool | int | float | str


class ParamError(ValueError):
    """A parameter name or value was rejected; the message says why."""


@dataclass(frozen=True)
class Param:
    name: str
    default: ParamValue
    min: float | None = None
    max: float | None = None
    unit: str = ""
    doc: str = ""
    choices: tuple[ParamValue, ...] = ()

    @property
    def type(self) -> type:
        return type(self.default)

    def check(self, value: object) -> ParamValue:
        """Return ``value`` converted to this parameter's type, or raise ParamError with the reason."""
        t = self.type
        if t is bool:
            if isinstance(value, bool):
                v: ParamValue = value
            elif isinstance(value, int) and value in (0, 1):
                v = bool(value)
            elif isinstance(value, str) and value.lower() in ("true", "false", "1", "0"):
                v = value.lower() in ("true", "1")
            else:
                raise ParamError(f"{self.name}: expected a boolean, got {value!r}")
        elif t is int:
            if isinstance(value, bool) or not isinstance(value, int | str | float):
                raise ParamError(f"{self.name}: expected an integer, got {value!r}")
            try:
                v = int(value) if not isinstance(value, float) else _int_from_float(self.name, value)
            except ValueError:
                raise ParamError(f"{self.name}: expected an integer, got {value!r}") from None
        elif t is float:
            if isinstance(value, bool) or not isinstance(value, int | float | str):
                raise ParamError(f"{self.name}: expected a number, got {value!r}")
            try:
                v = float(value)
            except ValueError:
                raise ParamError(f"{self.name}: expected a number, got {value!r}") from None
            if not math.isfinite(v):
                raise ParamError(f"{self.name}: {value!r} is not a finite number")
        else:
            if not isinstance(value, str):
                raise ParamError(f"{self.name}: expected a string, got {value!r}")
            v = value
        if self.choices and v not in self.choices:
            allowed = ", ".join(repr(c) for c in self.choices)
            raise ParamError(f"{self.name}: {v!r} is not one of {allowed}")
        if isinstance(v, int | float) and not isinstance(v, bool):
            if self.min is not None and v < self.min:
                raise ParamError(f"{self.name}: {v!r} is below the minimum {self.min:g}")
            if self.max is not None and v > self.max:
                raise ParamError(f"{self.name}: {v!r} is above the maximum {self.max:g}")
        return v

    def describe(self) -> dict[str, object]:
        return {
            "name": self.name,
            "type": self.type.__name__,
            "default": self.default,
            "min": self.min,
            "max": self.max,
            "unit": self.unit,
            "doc": self.doc,
            "choices": list(self.choices),
        }


def _int_from_float(name: str, value: float) -> int:
    if not value.is_integer():
        raise ParamError(f"{name}: expected an integer, got {value!r}")
    return int(value)


class ParamStore:
    """The values of one module's parameters.

    ``set`` may be called from any thread; the new value waits in a pending set until the module's
    loop calls ``take_changes`` between runs, so an algorithm never sees a value change mid-run.
    """

    def __init__(self, params: tuple[Param, ...], overrides: dict[str, object] | None = None) -> None:
        self.defs = {p.name: p for p in params}
        self._lock = threading.Lock()
        self._values: dict[str, ParamValue] = {p.name: p.default for p in params}
        self._pending: dict[str, ParamValue] = {}
        self.set_count = 0
        for name, value in (overrides or {}).items():
            self._values[name] = self.definition(name).check(value)

    def definition(self, name: str) -> Param:
        try:
            return self.defs[name]
        except KeyError:
            raise ParamError(f"unknown parameter '{name}'") from None

    def __getitem__(self, name: str) -> ParamValue:
        """The value the module currently runs with."""
        return self._values[name]

    def __contains__(self, name: str) -> bool:
        return name in self.defs

    def values(self) -> dict[str, ParamValue]:
        """Current values, including changes the module has not picked up yet."""
        with self._lock:
            return {**self._values, **self._pending}

    def set(self, name: str, value: object) -> tuple[ParamValue, ParamValue]:
        """Validate and queue a new value; returns (old, new). Raises ParamError, changing nothing."""
        new = self.definition(name).check(value)
        with self._lock:
            old = self._pending.get(name, self._values[name])
            if new != old:
                self._pending[name] = new
                self.set_count += 1
        return old, new

    def take_changes(self) -> set[str]:
        """Apply queued changes and return the names whose value changed (called by the module loop)."""
        if not self._pending:
            return set()
        with self._lock:
            pending, self._pending = self._pending, {}
        changed = {name for name, value in pending.items() if self._values[name] != value}
        self._values.update(pending)
        return changed
