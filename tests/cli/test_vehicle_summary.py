"""The vehicle's summary in `stack status` (PX4's `commander status`) from the vehicle's latest messages."""

from stack.cli.vehicle_summary import lines, summary
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import BatteryStatus, HomePosition, VehicleStatus

NS = VehicleStatus


def test_mode_armed_failsafe_position_battery():
    latest = {
        "vehicle_status": NS(nav_state=NS.NAVIGATION_STATE_AUTO_RTL, arming_state=NS.ARMING_STATE_ARMED, failsafe=True),
        "vehicle_local_position": VehicleLocalPosition(
            x=1.0, y=-2.0, z=-9.5, xy_valid=True, z_valid=True, ref_alt=488.0
        ),
        "home_position": HomePosition(z=0.5, valid_lpos=True),
        "battery_status": BatteryStatus(voltage_v=14.8, current_a=12.5, remaining=0.07, warning=2),
    }
    s = summary(latest, {"failsafe_action": "rtl", "failsafe_cause": "battery_critical"})
    assert (s["mode"], s["armed"], s["failsafe"], s["failsafe_cause"]) == ("Return", True, True, "battery_critical")
    assert lines(s) == [
        "vehicle: Return, armed, failsafe: rtl (battery_critical)",
        "position: N 1.00 E -2.00 D -9.50 m (local NED, valid), altitude 10.00 m above home, 497.5 m AMSL",
        "battery: 14.80 V, 12.5 A, 7 % remaining, warning critical",
    ]


def test_a_pack_without_a_current_sensor_says_so():
    # The simulated pack, as PX4's, measures no current (-1).
    latest = {"vehicle_status": NS(), "battery_status": BatteryStatus(voltage_v=16.2, current_a=-1.0, remaining=1.0)}
    s = summary(latest, {"failsafe_action": "none", "failsafe_cause": ""})
    assert lines(s)[-1] == "battery: 16.20 V, current unknown, 100 % remaining, warning none"


def test_a_quiet_vehicle_and_no_vehicle():
    s = summary({"vehicle_status": NS()}, {"failsafe_action": "none", "failsafe_cause": ""})
    assert lines(s) == ["vehicle: Manual, disarmed, failsafe: no"]
    assert lines(summary({}, None)) == ["vehicle: no vehicle_status (is a commander running?)"]


def test_the_dead_or_silent_control_modules_are_named():
    status = NS(nav_state=NS.NAVIGATION_STATE_TERMINATION, arming_state=NS.ARMING_STATE_ARMED, failsafe=True)
    status.control_lost_modules = ["mc_rate_control"]
    s = summary({"vehicle_status": status}, {"failsafe_action": "terminate", "failsafe_cause": "attitude_control_loss"})
    assert s["control_lost_modules"] == ["mc_rate_control"]
    assert lines(s) == [
        "vehicle: Termination, armed, failsafe: terminate (attitude_control_loss)",
        "control chain: mc_rate_control dead or silent",
    ]
