"""Which messages the simulated Pixhawk streams, how often, and how MAV_CMD_SET_MESSAGE_INTERVAL changes that.

The default rates are PX4's for a MAVLink instance in ONBOARD mode (``src/modules/mavlink/mavlink_main.cpp``,
``Mavlink::configure_streams_to_default``, ``case MAVLINK_MODE_ONBOARD``), for the messages simulated here.
GPS_RAW_INT is "unlimited" there: sent on every new GPS sample. SIM_STATE is not a PX4 stream; the simulated
Pixhawk sends its truth at 50 Hz so a scenario can be judged. HEARTBEAT is the link's own, at 1 Hz.

SET_MESSAGE_INTERVAL follows ``MavlinkReceiver::set_message_interval``: interval −1 stops the stream, 0 restores
its default, > 0 sets it (faster than the 250 Hz loop means every loop); HEARTBEAT and messages that are not
streams are refused. Streams are scheduled on their own due times (due += interval), so a 30 Hz stream on a
4 ms loop averages 30 Hz rather than rounding its period up to whole loops.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from pymavlink.dialects.v20 import common as mavlink

UNLIMITED = 0
"""Interval of a stream sent on every new sample (PX4's ``unlimited_rate``)."""
DISABLED = -1

ONBOARD_RATES_HZ: dict[int, float] = {
    mavlink.MAVLINK_MSG_ID_TIMESYNC: 10.0,
    mavlink.MAVLINK_MSG_ID_HIGHRES_IMU: 50.0,
    mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 30.0,
    mavlink.MAVLINK_MSG_ID_ATTITUDE: 100.0,
    mavlink.MAVLINK_MSG_ID_ODOMETRY: 30.0,
    mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 50.0,
    mavlink.MAVLINK_MSG_ID_ATTITUDE_TARGET: 10.0,
    mavlink.MAVLINK_MSG_ID_BATTERY_STATUS: 0.5,
    mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 5.0,
    mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 50.0,
    mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: 1.0,
    mavlink.MAVLINK_MSG_ID_GPS_RAW_INT: math.inf,
    mavlink.MAVLINK_MSG_ID_HOME_POSITION: 0.5,
    mavlink.MAVLINK_MSG_ID_SCALED_PRESSURE: 1.0,
    mavlink.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: 10.0,
    mavlink.MAVLINK_MSG_ID_SYS_STATUS: 5.0,
    mavlink.MAVLINK_MSG_ID_SYSTEM_TIME: 1.0,
    mavlink.MAVLINK_MSG_ID_VFR_HUD: 10.0,
    mavlink.MAVLINK_MSG_ID_SIM_STATE: 50.0,
}


def _interval_us(rate_hz: float) -> int:
    if rate_hz <= 0.0:
        return DISABLED
    return UNLIMITED if math.isinf(rate_hz) else round(1e6 / rate_hz)


class StreamScheduler:
    """Due times of the streams; ``due(now)`` lists the ones to send now, in the default table's order."""

    def __init__(self, default_rates_hz: Mapping[int, float] = ONBOARD_RATES_HZ) -> None:
        self._defaults = {msg_id: _interval_us(rate) for msg_id, rate in default_rates_hz.items()}
        self._intervals = dict(self._defaults)
        self._due: dict[int, int] = {}

    def streams(self) -> tuple[int, ...]:
        """The message ids streamed (whatever their interval now)."""
        return tuple(self._defaults)

    def interval_us(self, msg_id: int) -> int:
        """The interval now (MESSAGE_INTERVAL's convention: −1 disabled, 0 not available); unlimited streams
        report 0 too, as PX4 does."""
        return self._intervals.get(msg_id, 0)

    def set_interval(self, msg_id: int, interval_us: float) -> bool:
        """SET_MESSAGE_INTERVAL: False (refused) for HEARTBEAT or a message that is not a stream here."""
        if msg_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT or msg_id not in self._defaults:
            return False
        if interval_us < 0:
            self._intervals[msg_id] = DISABLED
        elif interval_us == 0:
            self._intervals[msg_id] = self._defaults[msg_id]
        else:
            self._intervals[msg_id] = max(round(interval_us), 1)
        self._due.pop(msg_id, None)
        return True

    def due(self, now_us: int) -> list[int]:
        """The streams due at ``now_us``; each is then scheduled one interval after its last due time, or after
        now when it fell more than an interval behind."""
        ready = []
        due_times = self._due
        for msg_id, interval in self._intervals.items():
            if interval == DISABLED:
                continue
            if interval == UNLIMITED:
                ready.append(msg_id)
                continue
            due = due_times.get(msg_id)
            if due is None or now_us >= due:
                ready.append(msg_id)
                due = now_us if due is None or now_us - due >= interval else due
                due_times[msg_id] = due + interval
        return ready
