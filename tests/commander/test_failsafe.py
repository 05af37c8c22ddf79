import pytest

from stack.commander import commands as C
from stack.commander.failsafe import FailsafeAction, mode_fallback, runnable_action
from stack.commander.modes import Requirement
from stack.commander.module import CommanderModule
from stack.commander.state_machine import ArmDisarmReason
from stack.msg.registry import ORB_ID
from stack.msg.system import BatteryWarning, TelemetryStatus
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import local_position, make_clock
from tests.support.bench import ModuleBench

POSITION_LOST = Requirement.LOCAL_POSITION | Requirement.LOCAL_POSITION_RELAXED | Requirement.LOCAL_ALT


def _in_mission(**params):
    """A vehicle flying a mission at 10 m, with a ground station connected."""
    clock = make_clock(**params)
    clock.overrides = {"mission_count": 5, "last_gcs_heartbeat_us": clock.t}
    clock.step()
    assert clock.send(C.mission_start_command(0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.fly_to((5.0, 0.0, -10.0))
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    return clock


def test_position_accuracy_lost_in_mission_lands():
    clock = _in_mission()
    clock.overrides["local_position"] = local_position(clock.t + clock.period, 5.0, 0.0, -10.0, eph=8.0)
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert out.vehicle_status.failsafe
    assert (out.failsafe_action, out.failsafe_cause) == ("land", "local_position_invalid")
    assert out.vehicle_status.nav_state_user_intention == NS.NAVIGATION_STATE_AUTO_MISSION
    assert any(e.startswith("Failsafe activated (local_position_invalid): land") for e in out.events)


def test_position_lost_in_mission_descends():
    clock = _in_mission()
    clock.overrides["local_position"] = None
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_DESCEND
    assert out.failsafe_action == "descend"
    assert out.vehicle_control_mode.flag_control_climb_rate_enabled
    assert not out.vehicle_control_mode.flag_control_position_enabled


def test_estimate_recovers_and_the_mission_continues():
    clock = _in_mission()
    clock.overrides["local_position"] = None
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_DESCEND
    del clock.overrides["local_position"]
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert out.failsafe_action == "none" and not out.vehicle_status.failsafe


def test_position_mode_falls_back_to_altitude_then_stabilized():
    clock = make_clock()
    clock.send(C.set_mode_command("posctl"))
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -5.0))
    clock.overrides = {"local_position": local_position(clock.t + clock.period, z=-5.0, xy_valid=False)}
    out = clock.step()
    assert (out.vehicle_status.nav_state, out.failsafe_action) == (NS.NAVIGATION_STATE_ALTCTL, "fallback_altctl")
    clock.overrides = {"local_position": None}
    out = clock.step()
    assert (out.vehicle_status.nav_state, out.failsafe_action) == (NS.NAVIGATION_STATE_STAB, "fallback_stabilized")


def test_command_link_loss_in_mission_returns():
    clock = _in_mission(NAV_DLL_ACT=2)
    heartbeat = clock.t
    clock.overrides["last_gcs_heartbeat_us"] = heartbeat
    out = clock.step(9.9)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert not out.vehicle_status.gcs_connection_lost
    out = clock.step(0.2)
    assert out.vehicle_status.gcs_connection_lost
    assert out.vehicle_status.gcs_connection_lost_counter == 1
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    assert (out.failsafe_action, out.failsafe_cause) == ("rtl", "gcs_connection_loss")


def test_command_link_loss_waits_com_fail_act_t_in_hold_first():
    clock = _in_mission(NAV_DLL_ACT=2, COM_FAIL_ACT_T=5.0)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    out = clock.step(10.1)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert (out.failsafe_action, out.failsafe_delayed_action) == ("hold", "rtl")
    assert clock.step(4.8).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    out = clock.step(0.3)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    assert out.failsafe_delayed_action == "none"


def test_a_link_regained_while_holding_before_the_return_returns_nothing():
    clock = _in_mission(NAV_DLL_ACT=2, COM_FAIL_ACT_T=5.0)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    out = clock.step(10.1)
    assert (out.vehicle_status.nav_state, out.failsafe_delayed_action) == (NS.NAVIGATION_STATE_AUTO_LOITER, "rtl")
    clock.step(2.0)
    clock.events.clear()
    clock.overrides["last_gcs_heartbeat_us"] = clock.t + clock.period  # the ground station is back
    out = clock.step()
    assert "Data link regained" in clock.events and not out.vehicle_status.gcs_connection_lost
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION  # the Hold ends with the loss
    assert (out.failsafe_action, out.failsafe_delayed_action) == ("none", "none")
    for _ in range(60):  # past the end of the delay, and beyond: no Return follows
        clock.overrides["last_gcs_heartbeat_us"] = clock.t + clock.period
        assert clock.step(0.1).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert not clock.step().vehicle_status.failsafe


def test_a_link_that_comes_and_goes_cannot_put_off_the_return_for_ever():
    # The delay runs on while the link is back: lost again, the vehicle waits out only what is left of it.
    clock = _in_mission(NAV_DLL_ACT=2, COM_FAIL_ACT_T=20.0, COM_DL_LOSS_T=5)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    assert clock.step(5.1).failsafe_delayed_action == "rtl"
    lost_at = clock.t
    clock.overrides["last_gcs_heartbeat_us"] = clock.t + clock.period  # one heartbeat, then lost again
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    out = clock.step(5.1)
    assert out.vehicle_status.gcs_connection_lost and out.failsafe_delayed_action == "rtl"
    out = clock.step(lost_at * 1e-6 + 19.9 - clock.t * 1e-6)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    out = clock.step(0.2)  # 20 s after the first loss, not after the second
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL and out.failsafe_delayed_action == "none"


def test_a_return_in_force_stays_when_the_link_comes_back():
    clock = _in_mission(NAV_DLL_ACT=2)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    assert clock.step(10.1).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    clock.overrides["last_gcs_heartbeat_us"] = clock.t + 5_000_000
    out = clock.step(1.0)
    assert not out.vehicle_status.gcs_connection_lost
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL  # until the user changes mode (PX4)


def test_only_a_ground_stations_heartbeat_is_the_data_link():
    bench = ModuleBench(CommanderModule)
    bench.now = 5_000_000
    bench.put(ORB_ID.telemetry_status, TelemetryStatus(heartbeat_type_onboard_controller=True))
    assert bench.module._inputs(bench.now).last_gcs_heartbeat_us == 0
    bench.now = 6_000_000
    bench.put(ORB_ID.telemetry_status, TelemetryStatus(heartbeat_type_gcs=True))
    assert bench.module._inputs(bench.now).last_gcs_heartbeat_us == 6_000_000


def test_link_loss_is_ignored_by_default_and_when_exempt():
    clock = _in_mission()
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    assert clock.step(12.0).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    clock = _in_mission(NAV_DLL_ACT=2, COM_DLL_EXCEPT=1)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    out = clock.step(12.0)
    assert out.vehicle_status.gcs_connection_lost
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION


def test_no_link_loss_before_a_first_heartbeat():
    clock = make_clock(NAV_DLL_ACT=2)
    clock.send(C.set_mode_command("hold"))
    clock.send(C.arm_command())
    out = clock.fly_to((0.0, 0.0, -5.0))
    assert not clock.step(30.0).vehicle_status.gcs_connection_lost
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER


def _position_mode_with_sticks(**params):
    """A vehicle holding 5 m in Position mode, flown with sticks from a ground station's joystick."""
    clock = make_clock(**params)
    clock.overrides = {"last_manual_control_us": clock.t, "manual_control_valid": True}
    clock.step()
    clock.send(C.set_mode_command("posctl"))
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -5.0))
    clock.overrides["last_manual_control_us"] = clock.t
    assert clock.status.nav_state == NS.NAVIGATION_STATE_POSCTL
    return clock


def test_manual_control_loss_returns_after_com_rc_loss_t():
    clock = _position_mode_with_sticks(COM_FAIL_ACT_T=0.0)
    out = clock.step(0.45)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_POSCTL and not out.vehicle_status.failsafe
    out = clock.step(0.1)
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    assert (out.failsafe_action, out.failsafe_cause) == ("rtl", "manual_control_loss")
    assert out.vehicle_status.nav_state_user_intention == NS.NAVIGATION_STATE_POSCTL


def test_sticks_marked_invalid_are_a_loss_at_once_and_valid_ones_a_recovery():
    clock = _position_mode_with_sticks(NAV_RCL_ACT=3, COM_FAIL_ACT_T=0.0)
    clock.overrides["manual_control_valid"] = False
    out = clock.step()
    assert (out.vehicle_status.nav_state, out.failsafe_cause) == (NS.NAVIGATION_STATE_AUTO_LAND, "manual_control_loss")
    assert "Manual control lost" in out.events
    clock.overrides.update(manual_control_valid=True, last_manual_control_us=clock.t + clock.period)
    out = clock.step()
    assert "Manual control regained" in out.events
    # Land stays until the pilot switches mode, as PX4's link-loss actions do.
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    clock.send(C.set_mode_command("posctl"))
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_POSCTL


@pytest.mark.parametrize(
    ("params", "acts"),
    [({"NAV_RCL_ACT": 0}, False), ({"COM_RCL_EXCEPT": 1}, False), ({"COM_RCL_EXCEPT": 2}, True), ({}, True)],
)
def test_manual_control_loss_in_mission_follows_nav_rcl_act_and_com_rcl_except(params, acts):
    clock = _in_mission(COM_FAIL_ACT_T=0.0, **params)
    clock.overrides["last_manual_control_us"] = clock.t
    clock.overrides["manual_control_valid"] = True
    out = clock.step(1.0)
    expected = NS.NAVIGATION_STATE_AUTO_RTL if acts else NS.NAVIGATION_STATE_AUTO_MISSION
    assert out.vehicle_status.nav_state == expected


def test_sticks_lost_before_arming_trigger_nothing_until_they_come_back_and_go_again():
    clock = make_clock(COM_FAIL_ACT_T=0.0)
    clock.overrides = {"last_manual_control_us": clock.t, "manual_control_valid": False}
    clock.step()
    clock.send(C.set_mode_command("hold"))
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -5.0))
    assert clock.step(2.0).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    clock.overrides.update(manual_control_valid=True, last_manual_control_us=clock.t + clock.period)
    clock.step()
    out = clock.step(1.0)
    assert (out.vehicle_status.nav_state, out.failsafe_cause) == (NS.NAVIGATION_STATE_AUTO_RTL, "manual_control_loss")


def test_no_manual_control_loss_before_any_sticks_nor_while_disarmed():
    clock = _in_mission(COM_FAIL_ACT_T=0.0)
    assert clock.step(5.0).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    clock = make_clock(COM_FAIL_ACT_T=0.0)
    clock.overrides = {"last_manual_control_us": clock.t, "manual_control_valid": True}
    out = clock.step(2.0)
    assert not out.vehicle_status.failsafe and out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_low_battery_warns_critical_returns_emergency_lands():
    clock = _in_mission(COM_LOW_BAT_ACT=3)
    clock.overrides["battery_warning"] = BatteryWarning.LOW
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert (out.failsafe_action, out.failsafe_cause) == ("warn", "battery_low")
    assert not out.vehicle_status.failsafe
    clock.overrides["battery_warning"] = BatteryWarning.CRITICAL
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    assert (out.failsafe_action, out.failsafe_cause) == ("rtl", "battery_critical")
    clock.overrides["battery_warning"] = BatteryWarning.EMERGENCY
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert (out.failsafe_action, out.failsafe_cause) == ("land", "battery_emergency")


@pytest.mark.parametrize(
    ("action", "critical", "emergency"), [(0, "warn", "warn"), (1, "rtl", "rtl"), (2, "land", "land")]
)
def test_com_low_bat_act_choices(action, critical, emergency):
    clock = _in_mission(COM_LOW_BAT_ACT=action)
    clock.overrides["battery_warning"] = BatteryWarning.CRITICAL
    assert clock.step().failsafe_action == critical
    clock.overrides["battery_warning"] = BatteryWarning.EMERGENCY
    assert clock.step().failsafe_action == emergency


def test_battery_already_low_at_arming_only_warns():
    clock = make_clock(COM_LOW_BAT_ACT=3)
    clock.overrides = {"battery_warning": BatteryWarning.CRITICAL}
    clock.step()
    clock.send(C.set_mode_command("hold"))
    clock.send(C.arm_command(force=True))
    out = clock.fly_to((0.0, 0.0, -5.0))
    assert out.failsafe_action == "warn"
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER


def test_geofence_breach_returns():
    clock = _in_mission(GF_ACTION=3, GF_MAX_HOR_DIST=50.0)
    assert clock.fly_to((49.0, 0.0, -10.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    out = clock.fly_to((40.0, 31.0, -10.0))
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    assert (out.failsafe_action, out.failsafe_cause) == ("rtl", "geofence_breach")
    # Coming back inside does not cancel the return: the action clears on a mode change or disarm.
    assert clock.fly_to((10.0, 0.0, -10.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL


def test_geofence_height_and_default_hold():
    clock = _in_mission(GF_MAX_VER_DIST=20.0)
    out = clock.fly_to((0.0, 0.0, -25.0))
    assert (out.vehicle_status.nav_state, out.failsafe_action) == (NS.NAVIGATION_STATE_AUTO_LOITER, "hold")


def test_user_takes_over_from_a_return_by_switching_mode():
    clock = _in_mission(GF_ACTION=3, GF_MAX_HOR_DIST=50.0)
    assert clock.fly_to((60.0, 0.0, -10.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    clock.sticks = True  # the pilot takes the sticks
    clock.step()
    assert clock.send(C.set_mode_command("posctl")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_POSCTL
    assert out.vehicle_status.failsafe_and_user_took_over
    assert not out.vehicle_status.failsafe
    assert out.failsafe_action == "warn"


def test_no_takeover_from_terminate():
    clock = _in_mission(GF_ACTION=4, GF_MAX_HOR_DIST=50.0)
    out = clock.fly_to((60.0, 0.0, -10.0))
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_TERMINATION
    assert out.actuator_armed.termination and out.vehicle_control_mode.flag_control_termination_enabled
    clock.send(C.set_mode_command("posctl"))
    assert clock.fly_to((0.0, 0.0, -10.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_TERMINATION


def test_disarm_action_disarms():
    clock = _in_mission(NAV_DLL_ACT=6)
    clock.overrides["last_gcs_heartbeat_us"] = clock.t
    out = clock.step(10.1)
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED
    assert out.vehicle_status.latest_disarming_reason == ArmDisarmReason.FAILSAFE


def test_already_landing_does_not_return():
    clock = _in_mission(COM_LOW_BAT_ACT=1)
    clock.send(C.land_command())
    clock.step()
    clock.overrides["battery_warning"] = BatteryWarning.CRITICAL
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert out.failsafe_action == "warn"


def test_fallback_chain():
    assert mode_fallback(Requirement.NONE, NS.NAVIGATION_STATE_POSCTL) == (
        FailsafeAction.NONE,
        NS.NAVIGATION_STATE_POSCTL,
    )
    assert mode_fallback(Requirement.MISSION, NS.NAVIGATION_STATE_AUTO_MISSION) == (
        FailsafeAction.RTL,
        NS.NAVIGATION_STATE_AUTO_RTL,
    )
    assert runnable_action(FailsafeAction.RTL, Requirement.HOME) == FailsafeAction.LAND
    assert runnable_action(FailsafeAction.HOLD, POSITION_LOST) == FailsafeAction.DESCEND
    assert runnable_action(FailsafeAction.RTL, POSITION_LOST | Requirement.ATTITUDE) == FailsafeAction.TERMINATE
    assert runnable_action(FailsafeAction.DISARM, POSITION_LOST) == FailsafeAction.DISARM
