"""Telemetry streams: which messages go out how often, changeable by MAV_CMD_SET_MESSAGE_INTERVAL.

One scheduler, parametrised by its table of default rates: PX4 configures each MAVLink instance's streams by its
mode (``src/modules/mavlink/mavlink_main.cpp``, ``Mavlink::configure_streams_to_default``). The stack's mavlink
module streams :data:`NORMAL_RATES_HZ` (MAVLINK_MODE_NORMAL, for the messages it provides); the simulated Pixhawk,
talking to a companion computer, :data:`ONBOARD_RATES_HZ` (MAVLINK_MODE_ONBOARD, for the messages it simulates).
A rate of ``math.inf`` is PX4's "unlimited" (``unlimited_rate``): the stream is offered on every call, and its
builder sends when there is a new sample. HEARTBEAT is never a stream: the link sends it at 1 Hz, always.

PX4 sends MISSION_CURRENT from its mission manager at 1 Hz and on change rather than as a stream; in the mavlink
module's table it is a stream too, so its rate can be changed like the others (changes are still sent at once).

SET_MESSAGE_INTERVAL (``common.xml``): param2 is the interval in µs, −1 disables the message, 0 restores its
default. :meth:`StreamScheduler.set_interval` is PX4's ``MavlinkReceiver::set_message_interval`` (any negative
interval stops the stream; HEARTBEAT and messages that are not streams are refused);
:meth:`StreamScheduler.set_message_interval` is the mavlink module's stricter answer (a MAV_RESULT: UNSUPPORTED
for a message not provided, DENIED for an interval that is not finite or negative other than −1).

Streams are scheduled on their own due times (due += interval), so a 30 Hz stream on a 4 ms loop averages 30 Hz
rather than rounding its period up to whole loops; after a gap longer than an interval a stream is sent once and
then scheduled from now, not in a burst.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from pymavlink.dialects.v20 import common as mavlink2

NORMAL_RATES_HZ: dict[int, float] = {
    mavlink2.MAVLINK_MSG_ID_SYS_STATUS: 1.0,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 1.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE: 15.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 10.0,
    mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 5.0,
    mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 1.0,
    mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT: 5.0,
    mavlink2.MAVLINK_MSG_ID_HOME_POSITION: 0.5,
    mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS: 0.5,
    mavlink2.MAVLINK_MSG_ID_VFR_HUD: 4.0,
    mavlink2.MAVLINK_MSG_ID_MISSION_CURRENT: 1.0,
}
"""MAVLINK_MODE_NORMAL, for the messages the stack's mavlink module provides."""

ONBOARD_RATES_HZ: dict[int, float] = {
    mavlink2.MAVLINK_MSG_ID_TIMESYNC: 10.0,
    mavlink2.MAVLINK_MSG_ID_HIGHRES_IMU: 50.0,
    mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 30.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE: 100.0,
    mavlink2.MAVLINK_MSG_ID_ODOMETRY: 30.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 50.0,
    mavlink2.MAVLINK_MSG_ID_ATTITUDE_TARGET: 10.0,
    mavlink2.MAVLINK_MSG_ID_BATTERY_STATUS: 0.5,
    mavlink2.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 5.0,
    mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 50.0,
    mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN: 1.0,
    mavlink2.MAVLINK_MSG_ID_GPS_RAW_INT: math.inf,
    mavlink2.MAVLINK_MSG_ID_HOME_POSITION: 0.5,
    mavlink2.MAVLINK_MSG_ID_SCALED_PRESSURE: 1.0,
    mavlink2.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: 10.0,
    mavlink2.MAVLINK_MSG_ID_SYS_STATUS: 5.0,
    mavlink2.MAVLINK_MSG_ID_SYSTEM_TIME: 1.0,
    mavlink2.MAVLINK_MSG_ID_VFR_HUD: 10.0,
}
"""MAVLINK_MODE_ONBOARD, for the messages the simulated Pixhawk provides (GPS_RAW_INT unlimited)."""

MIN_INTERVAL_US = 1_000
"""The fastest the mavlink module's streams may be asked to go (1 kHz)."""
UNLIMITED = 0
"""Interval of a stream sent on every new sample (PX4's ``unlimited_rate``)."""
DISABLED = -1

ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED
DENIED = mavlink2.MAV_RESULT_DENIED
UNSUPPORTED = mavlink2.MAV_RESULT_UNSUPPORTED


def _interval_us(rate_hz: float) -> int:
    if rate_hz <= 0.0:
        return DISABLED
    return UNLIMITED if math.isinf(rate_hz) else round(1e6 / rate_hz)


class StreamScheduler:
    """Which streams are due now, in the rate table's order; ``restart(now)`` when a link comes (back) into use.

    ``min_interval_us``: the shortest interval SET_MESSAGE_INTERVAL may set."""

    def __init__(self, rates_hz: Mapping[int, float] = NORMAL_RATES_HZ, min_interval_us: int = MIN_INTERVAL_US) -> None:
        self._defaults = {msg_id: _interval_us(hz) for msg_id, hz in rates_hz.items()}
        self._intervals = dict(self._defaults)
        self._min_interval_us = min_interval_us
        self._next: dict[int, int | None] = dict.fromkeys(self._defaults)
        """When each stream is next due; None: at once, then one interval from then."""

    def provides(self, msg_id: int) -> bool:
        return msg_id in self._defaults

    def streams(self) -> tuple[int, ...]:
        """The message ids streamed (whatever their interval now)."""
        return tuple(self._defaults)

    def interval_us(self, msg_id: int) -> int:
        """The current interval in µs, −1 when disabled (MESSAGE_INTERVAL's convention); 0 if not provided, and for
        an unlimited stream, as PX4 reports it."""
        return self._intervals.get(msg_id, 0)

    def set_interval(self, msg_id: int, interval_us: float) -> bool:
        """PX4's ``MavlinkReceiver::set_message_interval``: negative stops the stream, 0 restores its default, > 0
        sets it (at least ``min_interval_us``); False (refused) for HEARTBEAT or a message that is not a stream."""
        if msg_id == mavlink2.MAVLINK_MSG_ID_HEARTBEAT or not self.provides(msg_id):
            return False
        if interval_us < 0:
            self._intervals[msg_id] = DISABLED
        elif interval_us == 0:
            self._intervals[msg_id] = self._defaults[msg_id]
        else:
            self._intervals[msg_id] = max(self._min_interval_us, round(interval_us))
        self._next[msg_id] = None
        return True

    def set_message_interval(self, msg_id: float, interval_us: float) -> int:
        """MAV_CMD_SET_MESSAGE_INTERVAL as the mavlink module answers it: the MAV_RESULT (UNSUPPORTED for a message
        not provided, DENIED for an interval that is not finite, or negative other than −1)."""
        if not math.isfinite(msg_id) or msg_id != int(msg_id) or not self.provides(int(msg_id)):
            return UNSUPPORTED
        if not math.isfinite(interval_us) or (interval_us < 0 and interval_us != DISABLED):
            return DENIED
        if not self.set_interval(int(msg_id), interval_us):
            return UNSUPPORTED
        self._next[int(msg_id)] = 0  # due at once; then one interval after time 0, or after now when that is past
        return ACCEPTED

    def restart(self, now_us: int) -> None:
        """Everything is due at once (a link that was idle)."""
        for key in self._next:
            self._next[key] = now_us

    def due(self, now_us: int) -> list[int]:
        """The streams due at ``now_us``; each is then due one interval after its last due time, or one interval
        from now when it fell more than an interval behind."""
        out = []
        due_times = self._next
        for msg_id, interval in self._intervals.items():
            if interval == DISABLED:
                continue
            if interval == UNLIMITED:
                out.append(msg_id)
                continue
            due = due_times[msg_id]
            if due is not None and now_us < due:
                continue
            out.append(msg_id)
            following = due + interval if due is not None else now_us
            due_times[msg_id] = following if following > now_us else now_us + interval
        return out

    def next_due_us(self) -> int | None:
        """When the next stream is due (0: at once; None: all disabled)."""
        times = [t or 0 for msg_id, t in self._next.items() if self._intervals[msg_id] != DISABLED]
        return min(times) if times else None
