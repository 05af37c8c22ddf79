"""The values of one module's parameters, changeable while it runs.

A module declares the parameters it reads, defined in :mod:`stack.params.catalogue`; a launch profile may
override them; ``stack param set`` changes them at run time. Changes arrive on the parameter service's
thread and are applied by the module's own loop between runs, so an algorithm never sees a half-applied
update.
"""

from __future__ import annotations

import threading

from stack.params.param import Param, ParamError, ParamValue


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
