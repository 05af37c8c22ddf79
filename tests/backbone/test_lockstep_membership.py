"""The coordinator's member list, fed by liveliness tokens (no bus needed for the bookkeeping)."""

import threading

from stack.runtime.lockstep import LockstepCoordinator, _parse_member

TOKEN = "stack/v1/@lockstep/member/{name}/{pid}/topic/vehicle_local_position/0"


def coordinator_without_bus() -> LockstepCoordinator:
    c = LockstepCoordinator.__new__(LockstepCoordinator)
    c.now = 0
    c.members = {}
    c._triggered_by = {}
    c._events = []
    c._events_lock = threading.Lock()
    c._awaited = {}
    return c


def test_a_token_reported_twice_counts_its_member_once():
    # A liveliness subscriber with history may report a token both from its history and live; a
    # member counted twice would make the coordinator wait for an acknowledgement that never comes.
    c = coordinator_without_bus()
    member = _parse_member(TOKEN.format(name="flight_mode_manager", pid=7))
    again = _parse_member(TOKEN.format(name="flight_mode_manager", pid=7))
    other = _parse_member(TOKEN.format(name="mc_pos_control", pid=8))
    c._events = [("join", member), ("join", other)]
    c._apply_membership()
    c._events = [("join", again)]
    c._apply_membership()
    assert c._triggered_by == {"vehicle_local_position/0": [7, 8]}
    assert sorted(c.members) == [7, 8]
