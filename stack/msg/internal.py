"""Messages the runtime itself exchanges: module heartbeats and the lockstep protocol.

They travel under ``@``-prefixed keys (see :mod:`stack.bus.keys`), which Zenoh wildcards never
match, so recorders and topic listings see flight topics only.
"""

from __future__ import annotations

import msgspec

from stack.msg.base import Message


class ModuleHeartbeat(Message):
    """A module's presence and counters, published about once a second (wall time)."""

    module: str = ""
    pid: int = 0
    host: str = ""
    state: str = ""
    trigger: str = ""
    runs: int = 0
    msgs_in: int = 0
    msgs_out: int = 0
    decode_errors: int = 0
    schema_errors: int = 0
    rejected: int = 0
    foreign: int = 0
    loop_avg_us: float = 0.0
    loop_max_us: float = 0.0
    trigger_rate_hz: float = 0.0
    cpu_percent: float = 0.0
    rss_bytes: int = 0
    sim_time_us: int = 0
    extra: dict[str, float | int | str | bool] = msgspec.field(default_factory=dict)
    """The module's own figures (``Module.status``), e.g. a MAVLink link's counters."""
    invalid: int = 0
    """Messages refused for a value their type does not allow (stack.msg.validity)."""
    unauthorized: int = 0
    """Messages ignored for coming from a publisher the module does not hear (stack.bus.access)."""


class LockstepClock(Message):
    """One lockstep step: the new time and the cumulative publication counts up to the previous step.

    ``counts`` lists ``(publisher_id, topic_key, total)`` for every (publisher, topic) of the
    lockstep. Before acting at this time a subscriber waits until it holds message number ``total``
    of each topic it reads, so what every module sees is independent of process scheduling. As the
    counts are cumulative, a member that only needs the latest clock may drop older ones.
    ``members`` lists the publisher ids of the modules expected to act (and acknowledge) at this step.
    ``run`` is the run's random id (see stack.bus.topics.HEADER): members ignore clocks of other runs.
    """

    run: int = 0
    step: int = 0
    counts: list[tuple[int, str, int]] = msgspec.field(default_factory=list)
    members: list[int] = msgspec.field(default_factory=list)


class LockstepAck(Message):
    """A member finished one run at ``timestamp``, on the tick or on message ``trigger_index`` of
    ``trigger_publisher`` on ``trigger_topic``; ``published`` holds its new per-topic totals."""

    run: int = 0
    member: str = ""
    publisher_id: int = 0
    trigger_publisher: int = 0
    trigger_index: int = 0
    trigger_topic: str = ""
    published: list[tuple[str, int]] = msgspec.field(default_factory=list)
