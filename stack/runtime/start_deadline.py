"""How long a lockstep start-up may wait: the clock starts once the supervisor's roster is complete.

The supervisor starts a profile's modules one after another and gives each its own time to report ready
(:data:`stack.supervisor.supervisor.START_TIMEOUT_S`); on a loaded machine bringing up the whole roster can
take longer than one start-up timeout, and a module that began waiting when it came up would give up before
the last module was even started. So every wait of the lockstep start-up (a member's sync, the coordinator's
admission, the members over Zenoh of a shared-memory run) counts :data:`START_TIMEOUT_S` from the moment it
sees the roster complete. Before that the supervisor is in charge: a module that never comes up stops the
stack, and a module never outlives its supervisor (:mod:`stack.runtime.orphan`).
"""

from __future__ import annotations

import time

START_TIMEOUT_S = 60.0


class StartDeadline:
    """``passed(roster_complete)`` is true once ``timeout_s`` has gone by since the roster was first complete."""

    def __init__(self, timeout_s: float = START_TIMEOUT_S) -> None:
        self.timeout_s = timeout_s
        self._deadline: float | None = None

    def passed(self, roster_complete: bool) -> bool:
        now = time.monotonic()
        if self._deadline is None:
            if not roster_complete:
                return False
            self._deadline = now + self.timeout_s
        return now > self._deadline
