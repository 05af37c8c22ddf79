"""The severity the commander's events go out with on ``mavlink_log`` (STATUSTEXT for a ground station)."""

import pytest

from stack.commander.events import event_severity
from stack.msg.system import MavlinkLog


@pytest.mark.parametrize(
    ("text", "refused", "severity"),
    [
        ("Arming denied: no 3D GPS fix", True, MavlinkLog.SEVERITY_CRITICAL),
        ("Switching to Return is currently not possible: the vehicle is disarmed", True, MavlinkLog.SEVERITY_CRITICAL),
        ("Failsafe activated (gcs_connection_loss): rtl", False, MavlinkLog.SEVERITY_CRITICAL),
        ("Failsafe warning (battery_low)", False, MavlinkLog.SEVERITY_WARNING),
        ("Connection to ground station lost", False, MavlinkLog.SEVERITY_WARNING),
        ("Armed", False, MavlinkLog.SEVERITY_INFO),
        ("Mode: Hold", False, MavlinkLog.SEVERITY_INFO),
        ("Data link regained", False, MavlinkLog.SEVERITY_INFO),
    ],
)
def test_refusals_and_failsafes_are_critical_warnings_warn_the_rest_informs(text, refused, severity):
    assert event_severity(text, refused) == severity
