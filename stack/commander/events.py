"""How loud a commander event is for the operator: the MAV_SEVERITY its ``mavlink_log`` message carries.

PX4's commander sends arming refusals ("Arming denied: ...") and a failsafe taking over as critical, warnings
and link losses as warnings, and the rest (arming, mode changes) as information
(``src/modules/commander/Commander.cpp``, ``events::Log``).
"""

from __future__ import annotations

from stack.bus.host_beats import LOST_PREFIX
from stack.msg.system import MavlinkLog

WARNING_EVENTS = (
    "Failsafe warning",
    "Connection to ground station lost",
    "Link to the Pixhawk lost",
    "Commander stalled",
)
CRITICAL_EVENTS = ("Failsafe activated", LOST_PREFIX)


def event_severity(text: str, refused: bool) -> int:
    """The MAV_SEVERITY of a commander event; ``refused``: the text is a refused command's reason."""
    if refused or text.startswith(CRITICAL_EVENTS):
        return MavlinkLog.SEVERITY_CRITICAL
    if text.startswith(WARNING_EVENTS):
        return MavlinkLog.SEVERITY_WARNING
    return MavlinkLog.SEVERITY_INFO
