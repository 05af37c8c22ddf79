"""The coordinator's bookkeeping (no bus needed): its member list, fed by liveliness tokens, and the step's
accounts, fed by the members' acknowledgements."""

import threading
from types import SimpleNamespace

from stack.msg.internal import LockstepAck
from stack.runtime.ledger import Departures
from stack.runtime.lockstep import TIMER, LockstepCoordinator, MemberToken, parse_member

TOKEN = "stack/v1/@lockstep/member/{name}/{pid}/topic/vehicle_local_position/0"
TOPIC = "vehicle_local_position/0"


def coordinator_without_bus() -> LockstepCoordinator:
    c = LockstepCoordinator.__new__(LockstepCoordinator)
    c.now = 0
    c.members = {}
    c._triggered_by = {}
    c._events = []
    c._events_lock = threading.Lock()
    c._departures = Departures()
    c._totals, c._counters, c._where, c._bases = {}, [], {}, {}
    c.node = SimpleNamespace(publisher_id=1)
    c.barrier = SimpleNamespace(require=lambda *_: None)
    c._tick_pubs = {}
    return c


def test_a_token_reported_twice_counts_its_member_once():
    # A liveliness subscriber with history may report a token both from its history and live; a
    # member counted twice would make the coordinator wait for an acknowledgement that never comes.
    c = coordinator_without_bus()
    member = parse_member(TOKEN.format(name="flight_mode_manager", pid=7))
    again = parse_member(TOKEN.format(name="flight_mode_manager", pid=7))
    other = parse_member(TOKEN.format(name="mc_pos_control", pid=8))
    c._events = [("join", member), ("join", other)]
    c._apply_membership()
    c._events = [("join", again)]
    c._apply_membership()
    assert c._triggered_by == {"vehicle_local_position/0": [7, 8]}
    assert sorted(c.members) == [7, 8]


def commander_and_position_control() -> tuple[LockstepCoordinator, MemberToken]:
    """A coordinator with a timed commander (5), which publishes vehicle_local_position/0, and mc_pos_control (8),
    which that topic triggers; and mc_pos_control's member."""
    c = coordinator_without_bus()
    commander = parse_member("stack/v1/@lockstep/member/commander/5/timer/20000")
    pos = parse_member(TOKEN.format(name="mc_pos_control", pid=8))
    assert commander is not None and pos is not None
    c._events = [("join", commander), ("join", pos)]
    c._apply_membership()
    return c, pos


def test_a_step_waits_for_every_trigger_announced_whatever_order_the_acknowledgements_come_in():
    # A timed commander (5) publishes vehicle_local_position/0, which triggers mc_pos_control (8); the run of
    # mc_pos_control may be acknowledged before the commander's run that announced its trigger.
    c, _ = commander_and_position_control()
    c._counters[c._counter("ticks", 5)] += 1  # the step ticks the commander
    assert not c._ledger.complete(c._counters)
    c._handle_ack(LockstepAck(publisher_id=8, trigger_publisher=5, trigger_index=1, trigger_topic=TOPIC))
    assert not c._ledger.complete(c._counters)
    c._handle_ack(LockstepAck(publisher_id=5, trigger_topic=TIMER, published=[(TOPIC, 1)]))
    assert c._ledger.complete(c._counters)
    # The other order: the trigger is announced first, and the step waits for its run.
    c._counters[c._counter("ticks", 5)] += 1
    c._handle_ack(LockstepAck(publisher_id=5, trigger_topic=TIMER, published=[(TOPIC, 2)]))
    assert not c._ledger.complete(c._counters)
    assert [m.name for m, _ in c._ledger.with_work(c._counters)] == ["mc_pos_control"]
    c._handle_ack(LockstepAck(publisher_id=8, trigger_publisher=5, trigger_index=2, trigger_topic=TOPIC))
    assert c._ledger.complete(c._counters)


def test_a_member_that_rejoins_waits_only_for_triggers_written_after_it_came_back():
    c, pos = commander_and_position_control()
    c._counters[c._counter("ticks", 5)] += 1
    c._handle_ack(LockstepAck(publisher_id=5, trigger_topic=TIMER, published=[(TOPIC, 1)]))
    c._events = [("leave", pos)]
    c._apply_membership()
    assert c._ledger.complete(c._counters)  # nobody waits for the run of a member that left
    c._events = [("join", pos)]
    c._apply_membership()
    assert c._ledger.complete(c._counters)  # nor for message 1, written before it came back
