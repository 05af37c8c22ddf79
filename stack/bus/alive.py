"""Module processes' alive tokens, ``stack/<vehicle>/@alive/<module>/<pid>``, as the others read them.

Any peer on the bus can declare a liveliness token, so a key that is not a module name and a pid is dropped
and counted; the first one is reported once, in one line, and the rest only counted (a token is seen again
on every query and every change, and a flood of forged keys must not become a flood of log lines).
"""

from __future__ import annotations

import re
from collections.abc import Callable

import zenoh

from stack.bus import keys

_PID = re.compile(r"^[1-9][0-9]{0,9}$")


def parse_alive_token(key: str, vehicle: str) -> tuple[str, int] | None:
    """``stack/<vehicle>/@alive/<module>/<pid>`` → (module, pid), or None when the key is not one."""
    parts = key.split("/")
    if len(parts) != 5 or parts[:3] != [keys.ROOT, vehicle, "@alive"]:
        return None
    module, pid = parts[3], parts[4]
    try:
        keys.check_name("module", module)
    except ValueError:
        return None
    if not _PID.match(pid):
        return None
    return module, int(pid)


def vehicles_alive(session: zenoh.Session, timeout: float = 1.0) -> set[str]:
    """The vehicles with a module process alive on the bus (its alive token well formed)."""
    found = set()
    for reply in session.liveliness().get(keys.alive_query("*"), timeout=timeout):
        if reply.ok is None:
            continue
        key = str(reply.ok.key_expr)
        vehicle = key.split("/")[1]
        if keys.valid_name(vehicle) and parse_alive_token(key, vehicle) is not None:
            found.add(vehicle)
    return found


class AliveTokens:
    """Parses alive-token keys of one vehicle, counting the malformed ones and reporting the first through
    ``warn``."""

    def __init__(self, vehicle: str, warn: Callable[[str], None]) -> None:
        self.vehicle = vehicle
        self.malformed = 0
        self._warn = warn

    def parse(self, key: str) -> tuple[str, int] | None:
        parsed = parse_alive_token(key, self.vehicle)
        if parsed is None:
            self.malformed += 1
            if self.malformed == 1:
                self._warn(
                    f"ignored a malformed alive token {key!r} (not {keys.ROOT}/{self.vehicle}/@alive/<module>/<pid>);"
                    " any more are counted, not reported"
                )
        return parsed
