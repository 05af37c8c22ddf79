"""Names a user types (parameters, profiles, topics, scenarios, missions): the closest known one when a name is
not known, as a hint after the refusal."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def suggestion(name: str, known: Iterable[str]) -> str:
    """" (did you mean X?)" with the closest of ``known`` to ``name`` (case-insensitive), or ""."""
    by_upper = {k.upper(): k for k in known}
    close = difflib.get_close_matches(name.upper(), list(by_upper), n=1, cutoff=0.6)
    return f" (did you mean {by_upper[close[0]]}?)" if close else ""
