"""SET_ATTITUDE_TARGET as PX4 reads it, and the stream scheduler's timing."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink

from stack.mavlink.streams import StreamScheduler
from stack.pixhawk_sim.offboard import decode_attitude_target
from stack.pixhawk_sim.protocol import STREAM_RATES_HZ, stream_scheduler

ATTITUDE_IGNORE = mavlink.ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE
THROTTLE_IGNORE = mavlink.ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE
YAW_RATE_IGNORE = mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE
ROLL_RATE_IGNORE = mavlink.ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
ALL_RATES_IGNORE = 7


def target(mask: int, q=(1.0, 0.0, 0.0, 0.0), rates=(0.1, -0.2, 0.3), thrust=0.5):
    return mavlink.MAVLink_set_attitude_target_message(0, 1, 1, mask, list(q), *rates, thrust)


def test_body_rates_and_collective_thrust() -> None:
    sp = decode_attitude_target(target(ATTITUDE_IGNORE), None)
    assert sp is not None and not sp.is_attitude
    assert sp.rates == pytest.approx((0.1, -0.2, 0.3))
    assert sp.thrust_body == (0.0, 0.0, -0.5)  # FRD: up is -z
    sp = decode_attitude_target(target(ATTITUDE_IGNORE | ROLL_RATE_IGNORE, thrust=1.7), None)
    assert math.isnan(sp.rates[0]) and sp.rates[1] == pytest.approx(-0.2)
    assert sp.thrust_body == (0.0, 0.0, -1.0)


def test_attitude_with_yaw_rate_feed_forward_unless_ignored() -> None:
    q = (0.9, 0.1, 0.0, 0.0)
    sp = decode_attitude_target(target(ALL_RATES_IGNORE & ~YAW_RATE_IGNORE, q=q), None)
    assert sp.is_attitude and sp.q == pytest.approx(tuple(v / math.hypot(*q) for v in q))
    assert sp.rates[2] == pytest.approx(0.3)
    sp = decode_attitude_target(target(ALL_RATES_IGNORE, q=q), None)
    assert math.isnan(sp.rates[2])


def test_setpoints_that_carry_nothing() -> None:
    assert decode_attitude_target(target(ATTITUDE_IGNORE | ALL_RATES_IGNORE), None) is None
    assert decode_attitude_target(target(0, q=(0.0, 0.0, 0.0, 0.0)), None) is None
    assert decode_attitude_target(target(ATTITUDE_IGNORE, thrust=math.nan), None) is None
    assert decode_attitude_target(target(ATTITUDE_IGNORE | THROTTLE_IGNORE), None) is None


def test_throttle_ignore_keeps_the_previous_thrust() -> None:
    previous = decode_attitude_target(target(ATTITUDE_IGNORE, thrust=0.4), None)
    sp = decode_attitude_target(target(ATTITUDE_IGNORE | THROTTLE_IGNORE, thrust=0.9), previous)
    assert sp.thrust_body == (0.0, 0.0, -0.4)


def test_streams_average_their_rate_on_a_4_ms_loop() -> None:
    streams = stream_scheduler()
    counts: dict[int, int] = {}
    for step in range(1, 2501):  # 10 s at 250 Hz
        for msg_id in streams.due(step * 4000):
            counts[msg_id] = counts.get(msg_id, 0) + 1
    assert counts[mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED] == 300  # 30 Hz, not 250/9 = 27.8 Hz
    assert counts[mavlink.MAVLINK_MSG_ID_ATTITUDE] == 1000
    assert counts[mavlink.MAVLINK_MSG_ID_GPS_RAW_INT] == 2500  # unlimited: offered every loop
    assert set(counts) == set(STREAM_RATES_HZ)


def test_a_stream_resynchronises_after_a_stall_instead_of_bursting() -> None:
    streams = StreamScheduler({mavlink.MAVLINK_MSG_ID_ATTITUDE: 100.0})
    assert streams.due(0) == [mavlink.MAVLINK_MSG_ID_ATTITUDE]
    assert streams.due(5000) == []
    assert streams.due(1_000_000) == [mavlink.MAVLINK_MSG_ID_ATTITUDE]  # a 1 s stall: one message, not 100
    assert streams.due(1_004_000) == []
    assert streams.due(1_010_000) == [mavlink.MAVLINK_MSG_ID_ATTITUDE]


def test_intervals() -> None:
    streams = stream_scheduler()
    imu = mavlink.MAVLINK_MSG_ID_HIGHRES_IMU
    assert streams.interval_us(imu) == 20000
    assert streams.set_interval(imu, 2500.4) and streams.interval_us(imu) == 2500
    assert streams.set_interval(imu, -1) and streams.interval_us(imu) == -1
    assert streams.set_interval(imu, 0) and streams.interval_us(imu) == 20000
    assert not streams.set_interval(mavlink.MAVLINK_MSG_ID_HEARTBEAT, 100000)
    assert not streams.set_interval(mavlink.MAVLINK_MSG_ID_RC_CHANNELS, 100000)
    assert streams.interval_us(mavlink.MAVLINK_MSG_ID_RC_CHANNELS) == 0  # not available
