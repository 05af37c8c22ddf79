"""Telemetry streams: PX4's normal-mode rates, SET_MESSAGE_INTERVAL, and when each message is due."""

import math

from pymavlink.dialects.v20 import common as M

from stack.mavlink.streams import MIN_INTERVAL_US, NORMAL_RATES_HZ, StreamScheduler

ATTITUDE = M.MAVLINK_MSG_ID_ATTITUDE


def _sent_in(streams: StreamScheduler, seconds: float, tick_us: int = 10_000, start_us: int = 1_000_000) -> dict:
    counts: dict[int, int] = {}
    for t in range(start_us, start_us + round(seconds * 1e6), tick_us):
        for msg_id in streams.due(t):
            counts[msg_id] = counts.get(msg_id, 0) + 1
    return counts


def test_each_message_goes_out_at_px4s_normal_mode_rate():
    assert NORMAL_RATES_HZ[ATTITUDE] == 15.0 and NORMAL_RATES_HZ[M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT] == 5.0
    assert (
        NORMAL_RATES_HZ[M.MAVLINK_MSG_ID_HOME_POSITION] == 0.5 and NORMAL_RATES_HZ[M.MAVLINK_MSG_ID_SYS_STATUS] == 1.0
    )
    counts = _sent_in(StreamScheduler(), 10.0)
    for msg_id, hz in NORMAL_RATES_HZ.items():
        assert abs(counts[msg_id] - hz * 10.0) <= 1.0, (msg_id, counts[msg_id])


def test_set_message_interval_changes_disables_and_restores_a_stream():
    streams = StreamScheduler()
    assert streams.set_message_interval(ATTITUDE, 20_000) == M.MAV_RESULT_ACCEPTED
    assert streams.interval_us(ATTITUDE) == 20_000
    assert abs(_sent_in(streams, 2.0)[ATTITUDE] - 100) <= 1
    assert streams.set_message_interval(ATTITUDE, -1) == M.MAV_RESULT_ACCEPTED
    assert streams.interval_us(ATTITUDE) == -1 and ATTITUDE not in _sent_in(streams, 2.0)
    assert streams.set_message_interval(ATTITUDE, 0) == M.MAV_RESULT_ACCEPTED
    assert streams.interval_us(ATTITUDE) == round(1e6 / 15.0)
    assert streams.set_message_interval(ATTITUDE, 10) == M.MAV_RESULT_ACCEPTED
    assert streams.interval_us(ATTITUDE) == MIN_INTERVAL_US


def test_a_message_not_provided_is_unsupported_and_a_bad_interval_denied():
    streams = StreamScheduler()
    assert streams.set_message_interval(M.MAVLINK_MSG_ID_HIGHRES_IMU, 10_000) == M.MAV_RESULT_UNSUPPORTED
    assert streams.set_message_interval(math.nan, 10_000) == M.MAV_RESULT_UNSUPPORTED
    assert streams.set_message_interval(ATTITUDE + 0.5, 10_000) == M.MAV_RESULT_UNSUPPORTED
    for bad in (math.nan, math.inf, -5.0):
        assert streams.set_message_interval(ATTITUDE, bad) == M.MAV_RESULT_DENIED
    assert streams.interval_us(ATTITUDE) == round(1e6 / 15.0)
    assert streams.interval_us(M.MAVLINK_MSG_ID_HIGHRES_IMU) == 0


def test_after_an_idle_spell_every_stream_is_due_once_not_in_a_burst():
    streams = StreamScheduler()
    _sent_in(streams, 1.0)
    streams.restart(60_000_000)
    assert set(streams.due(60_000_000)) == set(NORMAL_RATES_HZ)
    assert streams.due(60_000_001) == []
    assert streams.next_due_us() == 60_000_000 + round(1e6 / 15.0)
