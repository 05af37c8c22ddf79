"""What the pixhawk module makes of its link, as I/O-free library code: a sample's time on the stack's clock,
whether the Pixhawk is heard, the stream checks, which COMMAND_ACKs are the adapter's, and the status it
publishes."""

from pymavlink.dialects.v20 import common as M

from stack.mavlink import px4_modes
from stack.mavlink.link import LinkCounters
from stack.mavlink.px4_modes import Px4Mode
from stack.mavlink.timesync import TimeSync
from stack.pixhawk import plant
from stack.pixhawk.link_state import (
    SILENCE_US,
    STREAM_CHECK_US,
    STREAM_REQUESTS,
    Liveness,
    StreamWatch,
    ack_for_adapter,
    external_status,
    sample_us,
)

LINK_TIMEOUT_US = 3_000_000


def _synced(offset_us: int) -> TimeSync:
    """A time sync that has seen enough replies with the peer ``offset_us`` behind us (rtt 0)."""
    ts = TimeSync()
    now = 10_000_000
    while not ts.synced:
        ts1 = ts.request(now)
        ts.on_reply((now - offset_us) * 1000, ts1, now)
        now += 100_000
    return ts


def test_a_sample_time_is_the_arrival_until_synced_then_mapped_and_never_later_than_arrival():
    assert sample_us(TimeSync(), 5_000, 90_000_000) == 90_000_000
    ts = _synced(offset_us=7_000_000)
    assert sample_us(ts, 80_000_000, 90_000_000) == 87_000_000
    assert sample_us(ts, 85_000_000, 90_000_000) == 90_000_000  # would be after it arrived
    unix = 1_700_000_000_000_000
    assert sample_us(ts, unix, 90_000_000) == 90_000_000  # a Unix time is not the Pixhawk's boot clock


def test_the_pixhawk_is_heard_while_data_flows_and_its_heartbeat_is_fresh_or_not_yet_due_after_a_gap():
    live = Liveness()
    assert not live.connected(SILENCE_US, True, True, LINK_TIMEOUT_US)  # nothing received yet
    live.on_receive(10_000_000)
    assert not live.connected(10_000_000, False, True, LINK_TIMEOUT_US)  # no HEARTBEAT from it seen yet
    assert live.connected(10_000_000, True, False, LINK_TIMEOUT_US)  # data just came back: heartbeat not due
    assert not live.connected(10_000_000 + LINK_TIMEOUT_US - 1, True, False, LINK_TIMEOUT_US)  # silent since
    for t in range(10_100_000, 10_000_000 + LINK_TIMEOUT_US, 100_000):
        live.on_receive(t)  # data without a gap: resumed stays at 10 s
    t = 10_000_000 + LINK_TIMEOUT_US
    live.on_receive(t)
    assert not live.connected(t, True, False, LINK_TIMEOUT_US)  # the heartbeat is overdue
    assert live.connected(t, True, True, LINK_TIMEOUT_US)
    assert not live.connected(t + SILENCE_US, True, True, LINK_TIMEOUT_US)  # data stopped


def test_streams_are_asked_for_then_again_while_slow_at_most_a_few_times_per_connection():
    imu, gps = plant.Stream(M.MAVLink_highres_imu_message, 100.0), plant.Stream(M.MAVLink_gps_raw_int_message, 0.0)
    watch = StreamWatch([imu, gps])
    assert watch.check(STREAM_CHECK_US, connected=False) == []
    t = STREAM_CHECK_US
    assert [c.params[0] for c in watch.check(t, True)] == [imu.msg_id, gps.msg_id]  # each asked once
    assert watch.check(t + STREAM_CHECK_US - 1, True) == []  # not yet time
    for _ in range(60):
        watch.on_message(imu.msg_id)
    t += STREAM_CHECK_US
    assert watch.check(t, True) == []  # 60 in 1 s ≥ half of 100 Hz; the stopped one stayed silent
    watch.on_message(gps.msg_id)  # a stream asked off still arriving
    t += STREAM_CHECK_US
    asked = watch.check(t, True)  # and the IMU slow (none)
    assert [(c.params[0], c.params[1]) for c in asked] == [(imu.msg_id, 10_000.0), (gps.msg_id, -1.0)]
    for _ in range(STREAM_REQUESTS):
        t += STREAM_CHECK_US
        watch.check(t, True)
    assert watch.requests[imu.msg_id] == STREAM_REQUESTS
    t += STREAM_CHECK_US
    assert watch.check(t, True) == []  # given up until the link reconnects
    watch.check(t, False)
    t += STREAM_CHECK_US
    assert len(watch.check(t, True)) == 2


def test_a_command_ack_is_the_adapters_when_addressed_to_it_or_broadcast():
    assert ack_for_adapter(1, 191, 1) and ack_for_adapter(0, 0, 1) and ack_for_adapter(1, 0, 1)
    assert not ack_for_adapter(2, 191, 1) and not ack_for_adapter(1, 190, 1)


def test_the_status_says_what_the_heartbeat_said_who_flies_and_the_links_health():
    handoff = plant.Handoff()
    counters = LinkCounters(link_losses=2, quality=0.75)
    idle = external_status(5, handoff, None, counters)
    assert (idle.timestamp, idle.system_id, idle.autopilot, idle.mode, idle.link_losses) == (5, 0, 0, "", 2)
    handoff.on_connection(1_000, True)
    handoff.on_heartbeat(1_000, M.MAV_MODE_FLAG_SAFETY_ARMED, px4_modes.encode(Px4Mode.OFFBOARD), M.MAV_STATE_ACTIVE)
    status = external_status(2_000, handoff, (1, 1), counters)
    assert (status.system_id, status.component_id, status.autopilot) == (1, 1, M.MAV_AUTOPILOT_PX4)
    assert status.connected and status.armed and status.offboard
    assert status.mode == px4_modes.describe(px4_modes.encode(Px4Mode.OFFBOARD))
    assert status.link_quality == 0.75 and status.in_control == handoff.in_control
