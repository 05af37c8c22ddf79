"""Who is on the link (wall clock) and the telemetry_status the commander's data-link-loss failsafe reads."""

import itertools

from pymavlink.dialects.v20 import common as M

from stack.mavlink.clock import StampClock
from stack.mavlink.presence import HEARTBEAT_TIMEOUT_US, PEER_TIMEOUT_US, TELEMETRY_PERIOD_US, Presence

OWN = (1, 1)
GCS = (255, 190)


def test_a_ground_station_is_reported_often_while_heard_then_once_as_gone():
    presence = Presence(OWN)
    assert presence.telemetry_due(0) is None
    presence.on_message(GCS, 1_000_000, M.MAV_TYPE_GCS)
    reports = [(t, presence.telemetry_due(t)) for t in range(1_000_000, 4_000_000, 10_000)]
    sent = [(t, flags) for t, flags in reports if flags is not None]
    alive = [t for t, flags in sent if flags == (True, False)]
    assert alive[0] == 1_000_000 and all(b - a == TELEMETRY_PERIOD_US for a, b in itertools.pairwise(alive))
    assert alive[-1] < 1_000_000 + HEARTBEAT_TIMEOUT_US
    assert [flags for _, flags in sent if flags != (True, False)] == [(False, False)]
    assert presence.telemetry_due(10_000_000) is None


def test_only_ground_station_and_onboard_heartbeats_count_and_our_own_never():
    presence = Presence(OWN)
    presence.on_message(OWN, 0, M.MAV_TYPE_GCS)
    presence.on_message((2, 1), 0, M.MAV_TYPE_QUADROTOR)
    assert not presence.gcs(0) and presence.telemetry_due(0) is None
    presence.on_message((1, 191), 0, M.MAV_TYPE_ONBOARD_CONTROLLER)
    assert presence.telemetry_due(0) == (False, True)


def test_any_message_keeps_the_link_in_use_for_a_while():
    presence = Presence(OWN)
    assert not presence.active(0)
    presence.on_message(GCS, 1_000_000)  # not a heartbeat: in use, but no ground station reported
    assert presence.active(1_000_000 + PEER_TIMEOUT_US - 1) and not presence.gcs(1_000_000)
    assert not presence.active(1_000_000 + PEER_TIMEOUT_US)


def test_the_stamp_is_the_latest_simulated_time_in_lockstep_and_the_wall_clock_otherwise():
    lockstep = StampClock(True, lambda: 123)
    assert lockstep.now() == 0
    for t in (5_000, 9_000, 7_000):
        lockstep.observe(t)
    assert lockstep.now() == 9_000
    assert StampClock(False, lambda: 123).now() == 123
