"""The commands the mavlink module answers itself rather than forwarding to the commander, I/O-free.

PX4's mavlink module handles these in ``MavlinkReceiver::handle_message_command_both``
(``src/modules/mavlink/mavlink_receiver.cpp``): MAV_CMD_SET_MESSAGE_INTERVAL, MAV_CMD_GET_MESSAGE_INTERVAL,
MAV_CMD_REQUEST_MESSAGE and MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES. Each answer is the MAV_RESULT, the index of
the offending parameter (COMMAND_ACK's ``result_param2``, 0 for none) and the messages to send after the ACK, as
the MAVLink command protocol has them follow it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink.streams import StreamScheduler

M = mavlink2
Answer = tuple[int, int, list[mavlink2.MAVLink_message]]
"""MAV_RESULT, the offending parameter, the messages to send after the ACK."""
Builders = Mapping[int, Callable[[], mavlink2.MAVLink_message | None]]
"""What the module can send on request: message id → a builder (None: provided, but no data for it yet)."""

COMMANDS = frozenset(
    {
        M.MAV_CMD_SET_MESSAGE_INTERVAL,
        M.MAV_CMD_GET_MESSAGE_INTERVAL,
        M.MAV_CMD_REQUEST_MESSAGE,
        M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
    }
)


def _whole(value: float) -> bool:
    return math.isfinite(value) and value == int(value)


def set_message_interval(streams: StreamScheduler, msg_id: float, interval_us: float) -> Answer:
    result = streams.set_message_interval(msg_id, interval_us)
    return result, (2 if result == M.MAV_RESULT_DENIED else 0), []


def get_message_interval(streams: StreamScheduler, msg_id: float) -> Answer:
    if not _whole(msg_id) or not 0 <= msg_id < 2**24:
        return M.MAV_RESULT_DENIED, 1, []
    interval = M.MAVLink_message_interval_message(int(msg_id), streams.interval_us(int(msg_id)))
    return M.MAV_RESULT_ACCEPTED, 0, [interval]


def request_message(builders: Builders, msg_id: float) -> Answer:
    if not _whole(msg_id):
        return M.MAV_RESULT_DENIED, 1, []
    build = builders.get(int(msg_id))
    if build is None:
        return M.MAV_RESULT_UNSUPPORTED, 0, []
    message = build()
    if message is None:
        return M.MAV_RESULT_TEMPORARILY_REJECTED, 0, []  # provided, but there is no data for it yet
    return M.MAV_RESULT_ACCEPTED, 0, [message]


def answer(command: int, param1: float, param2: float, streams: StreamScheduler, builders: Builders) -> Answer | None:
    """The answer to ``command`` if it is one of :data:`COMMANDS`, else None (the commander's to answer)."""
    if command == M.MAV_CMD_SET_MESSAGE_INTERVAL:
        return set_message_interval(streams, param1, param2)
    if command == M.MAV_CMD_GET_MESSAGE_INTERVAL:
        return get_message_interval(streams, param1)
    if command == M.MAV_CMD_REQUEST_MESSAGE:
        return request_message(builders, param1)
    if command == M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
        return request_message(builders, M.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    return None
