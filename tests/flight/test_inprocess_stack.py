"""A scenario flown in one process (stack.scenario.inprocess) is the ``stack fly`` flight, bit for bit.

``stack fly attitude_step --seed 3 --record`` (the flight the determinism test flies too) runs every module in
its own process; the same scenario
and seed flown by :class:`stack.runtime.inprocess.InProcessStack` runs the same module classes in
this process. Every message the recorder caught up to the scenario's last tick (after it, the
supervisor stops the processes on the wall clock) must be one the in-process flight published, with
the same topic, instance, publisher, topic index, publication time, flags and payload, and none may
be missing.

Being the same flight, at a fraction of the CPU, an in-process flight is how the other tests check a
scenario's figures (tests/flight/conftest.py, ``fly_here``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

import pytest

from stack.scenario.inprocess import fly_in_process
from tests.flight.flights import Flight

Fly = Callable[..., Flight]

SCENARIO, SEED = "attitude_step", 3

Header = tuple[str, int, int, int, int, int]  # topic, instance, publisher, index, publication time, flags


@pytest.mark.flight
def test_a_flight_in_process_is_the_multiprocess_flight(fly: Fly) -> None:
    flight = fly(SEED, 0)  # attitude_step over the shared-memory fast path, as in test_determinism
    inproc = fly_in_process(SCENARIO, seed=SEED, record=True)
    assert inproc.result["passed"] and flight.report["passed"]

    mine: dict[Header, bytes] = {
        (m.topic, m.instance, m.publisher_id, m.index, m.pub_time_us, m.flags): m.payload for m in inproc.published
    }
    theirs: dict[Header, bytes] = {
        (m.topic, m.instance, m.publisher_id, m.index, m.pub_time_us, m.flags): m.wire_payload()
        for m in flight.messages()
        if m.pub_time_us <= inproc.end_us
    }
    assert len(mine) == len(inproc.published) > 50_000  # every header is unique
    missing, extra = sorted(mine.keys() - theirs.keys()), sorted(theirs.keys() - mine.keys())
    assert not missing and not extra, (
        f"only in process: {Counter(h[0] for h in missing)}, first {missing[:3]}; "
        f"only in the recording: {Counter(h[0] for h in extra)}, first {extra[:3]}"
    )
    differ = sorted((h for h in mine if mine[h] != theirs[h]), key=lambda h: h[4])
    assert not differ, f"{len(differ)} payloads differ, from {differ[0]} on ({Counter(h[0] for h in differ)})"
    assert inproc.result["metrics"] == flight.report["metrics"]
    assert inproc.result["sim_time_s"] == flight.report["sim_time_s"]

