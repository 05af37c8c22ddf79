"""Mission progress for a ground station: MISSION_CURRENT and MISSION_ITEM_REACHED from ``mission_result``.

MISSION_CURRENT carries the current item, the number of items and ``mission_state`` (MISSION_STATE, a MAVLink 2
extension): NO_MISSION without a valid mission, NOT_STARTED before the first item is reached, ACTIVE while the
vehicle flies it (Mission mode), PAUSED when it left Mission mode mid-way, COMPLETE once the last item is reached
— which is what tells MAVSDK the mission is finished (a trailing DO item is never "reached" by flying).
``mission_mode`` is 1 in Mission mode, 2 otherwise. Both are sent when they change (and MISSION_CURRENT also as
a stream); MISSION_ITEM_REACHED once for each item reached, as PX4's mission manager does
(``src/modules/mavlink/mavlink_mission.cpp``), also for the items the navigator passes in one step.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink2

from stack.msg.navigation import MissionResult
from stack.msg.system import VehicleStatus

NS = VehicleStatus
IN_MISSION_MODE = 1
SUSPENDED = 2


def mission_state(result: MissionResult | None, nav_state: int) -> int:
    if result is None or not result.valid or result.seq_total <= 0:
        return mavlink2.MISSION_STATE_NO_MISSION
    if result.finished:
        return mavlink2.MISSION_STATE_COMPLETE
    if nav_state == NS.NAVIGATION_STATE_AUTO_MISSION:
        return mavlink2.MISSION_STATE_ACTIVE
    if result.seq_reached < 0:
        return mavlink2.MISSION_STATE_NOT_STARTED
    return mavlink2.MISSION_STATE_PAUSED


def mission_current(result: MissionResult | None, nav_state: int) -> mavlink2.MAVLink_mission_current_message:
    valid = result is not None and result.valid
    seq = result.seq_current if valid and result is not None else 0
    total = result.seq_total if valid and result is not None else 0
    mode = IN_MISSION_MODE if nav_state == NS.NAVIGATION_STATE_AUTO_MISSION else SUSPENDED
    return mavlink2.MAVLink_mission_current_message(seq, total, mission_state(result, nav_state), mode)


class MissionProgress:
    """``update`` with each ``mission_result`` / ``vehicle_status``: the messages to send at once."""

    def __init__(self) -> None:
        self.result: MissionResult | None = None
        self.nav_state = -1
        self._sent: tuple[int, int, int, int] | None = None
        self._reached: tuple[int, int] | None = None

    def current(self) -> mavlink2.MAVLink_mission_current_message:
        return mission_current(self.result, self.nav_state)

    def update(self, result: MissionResult | None, nav_state: int) -> list[mavlink2.MAVLink_message]:
        self.result = result
        self.nav_state = nav_state
        out: list[mavlink2.MAVLink_message] = []
        if result is not None and result.valid and result.seq_reached < 0:
            self._reached = (result.mission_id, -1)
        elif result is not None and result.valid:
            last = self._reached
            first = result.seq_reached
            if last is not None and last[0] == result.mission_id and last[1] < result.seq_reached:
                first = last[1] + 1  # items passed in one step (a DO item right after a waypoint) count too
            if last != (result.mission_id, result.seq_reached):
                self._reached = (result.mission_id, result.seq_reached)
                out.extend(
                    mavlink2.MAVLink_mission_item_reached_message(s) for s in range(first, result.seq_reached + 1)
                )
        current = self.current()
        key = (current.seq, current.total, current.mission_state, current.mission_mode)
        if key != self._sent:
            self._sent = key
            out.append(current)
        return out
