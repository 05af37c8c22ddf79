"""Telemetry streams: which messages go out how often, changeable by MAV_CMD_SET_MESSAGE_INTERVAL.

The default rates are PX4's "normal" mode (``src/modules/mavlink/mavlink_main.cpp``,
``Mavlink::configure_streams_to_default``, MAVLINK_MODE_NORMAL) for the messages this module provides. PX4 sends
MISSION_CURRENT from its mission manager at 1 Hz and on change rather than as a stream; here it is a stream too,
so its rate can be changed like the others (changes are still sent at once). HEARTBEAT is not a stream: it goes
out at 1 Hz, always.

SET_MESSAGE_INTERVAL (``common.xml``): param2 is the interval in µs, −1 disables the message, 0 restores its
default; rates are wall-clock rates, and a message is sent at most as often as its data is published.
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
MIN_INTERVAL_US = 1_000
"""The fastest a stream may be asked to go (1 kHz)."""
DISABLED = -1

ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED
DENIED = mavlink2.MAV_RESULT_DENIED
UNSUPPORTED = mavlink2.MAV_RESULT_UNSUPPORTED


def _interval_us(rate_hz: float) -> int:
    return round(1e6 / rate_hz) if rate_hz > 0.0 else DISABLED


class StreamScheduler:
    """Which streams are due now; ``restart(now)`` when a link comes (back) into use."""

    def __init__(self, rates_hz: Mapping[int, float] = NORMAL_RATES_HZ) -> None:
        self._defaults = {msg_id: _interval_us(hz) for msg_id, hz in rates_hz.items()}
        self._intervals = dict(self._defaults)
        self._next: dict[int, int] = dict.fromkeys(self._defaults, 0)

    def provides(self, msg_id: int) -> bool:
        return msg_id in self._defaults

    def interval_us(self, msg_id: int) -> int:
        """The current interval in µs, −1 when disabled (MESSAGE_INTERVAL's convention); 0 if not provided."""
        return self._intervals.get(msg_id, 0)

    def set_interval(self, msg_id: float, interval_us: float) -> int:
        """MAV_CMD_SET_MESSAGE_INTERVAL; returns the MAV_RESULT (UNSUPPORTED for a message not provided)."""
        if not math.isfinite(msg_id) or msg_id != int(msg_id) or not self.provides(int(msg_id)):
            return UNSUPPORTED
        if not math.isfinite(interval_us) or (interval_us < 0 and interval_us != DISABLED):
            return DENIED
        key = int(msg_id)
        if interval_us == 0:
            self._intervals[key] = self._defaults[key]
        elif interval_us == DISABLED:
            self._intervals[key] = DISABLED
        else:
            self._intervals[key] = max(MIN_INTERVAL_US, round(interval_us))
        self._next[key] = 0
        return ACCEPTED

    def restart(self, now_us: int) -> None:
        """Everything is due at once (a link that was idle)."""
        for key in self._next:
            self._next[key] = now_us

    def due(self, now_us: int) -> list[int]:
        """The messages to send now; each is then due again one interval later (or one from now, after a gap)."""
        out = []
        for msg_id, next_us in self._next.items():
            interval = self._intervals[msg_id]
            if interval == DISABLED or now_us < next_us:
                continue
            out.append(msg_id)
            following = next_us + interval
            self._next[msg_id] = following if following > now_us else now_us + interval
        return out

    def next_due_us(self) -> int | None:
        """When the next stream is due (None: all disabled)."""
        times = [t for msg_id, t in self._next.items() if self._intervals[msg_id] != DISABLED]
        return min(times) if times else None
