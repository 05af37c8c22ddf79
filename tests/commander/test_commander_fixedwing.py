"""The commander flying a plane (MAV_TYPE 1): its modes, takeoff, pre-arm airspeed check, failsafes, landing."""

import math

import pytest

from stack.commander import commands as C
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import local_position, make_clock
from tests.commander.plane_helpers import flying_plane, plane_clock

ACCEPTED = ACK.VEHICLE_CMD_RESULT_ACCEPTED


@pytest.mark.parametrize(
    ("command", "name"),
    [
        (C.set_nav_state_command(NS.NAVIGATION_STATE_EXTERNAL1), "RotorS"),
        (C.set_mode_command("rotors"), "RotorS"),  # PX4's custom mode (4, 11), as a ground station sends it
        (C.set_nav_state_command(NS.NAVIGATION_STATE_RATTITUDE), "Rattitude"),
    ],
)
def test_the_multicopter_modes_are_refused_on_a_plane_with_the_reason(command, name):
    clock = plane_clock()
    ack = clock.send(command)
    assert ack.result == ACK.VEHICLE_CMD_RESULT_DENIED
    assert ack.reason == f"{name} mode is not available on a fixed-wing vehicle"
    assert clock.step().vehicle_status.nav_state_user_intention == NS.NAVIGATION_STATE_MANUAL
    # A multicopter has them.
    assert make_clock().send(command).result == ACCEPTED


@pytest.mark.parametrize(
    "mode", ["manual", "stabilized", "acro", "altctl", "posctl", "auto:loiter", "auto:takeoff", "offboard"]
)
def test_the_plane_modes_are_selectable_on_the_ground(mode):
    clock = plane_clock()
    assert clock.send(C.set_mode_command(mode)).result == ACCEPTED


def test_takeoff_is_accepted_on_the_ground_and_ends_in_hold_at_the_fixed_wing_acceptance():
    clock = plane_clock()
    clock.step()
    ack = clock.send(C.takeoff_command(30.0))
    assert ack.result == ACCEPTED
    out = clock.step()
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    assert out.navigation.takeoff_altitude == 30.0
    # The runway roll: at the takeoff point, not yet flying.
    clock.airspeed = 12.0
    clock.step(1.0)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    # Within NAV_FW_ALT_RAD 10 m of 30 m: 20 m above home; 19.9 m is not yet.
    clock.fly_to((50.0, 0.0, -19.9))
    clock.step(0.5)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    clock.fly_to((60.0, 0.0, -20.0))
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert clock.status.nav_state_user_intention == NS.NAVIGATION_STATE_AUTO_LOITER
    assert "Takeoff complete, switching to Hold" in clock.events


def test_a_low_takeoff_altitude_ends_at_half_of_it_not_on_the_runway():
    clock = plane_clock()
    clock.step()
    assert clock.send(C.takeoff_command()).result == ACCEPTED  # MIS_TAKEOFF_ALT 2.5 m, below NAV_FW_ALT_RAD
    clock.landed = False  # rolling fast on the runway: the land detector says flying
    clock.step(1.0)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    clock.fly_to((40.0, 0.0, -1.2))
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    clock.fly_to((45.0, 0.0, -1.25))  # half of 2.5 m
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER


def test_a_multicopter_still_ends_its_takeoff_within_nav_mc_alt_rad():
    clock = make_clock()
    clock.step()
    assert clock.send(C.takeoff_command(30.0)).result == ACCEPTED
    clock.fly_to((0.0, 0.0, -29.1))
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    clock.fly_to((0.0, 0.0, -29.2))  # 30 − NAV_MC_ALT_RAD 0.8
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER


def test_a_takeoff_in_flight_is_refused():
    clock = flying_plane()
    ack = clock.send(C.takeoff_command(30.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED and "already flying" in ack.reason


@pytest.mark.parametrize(
    ("airspeed", "fresh", "reason"),
    [
        (0.0, False, "Arming denied: no airspeed data"),
        (math.nan, True, "Arming denied: airspeed invalid"),
        (21.0, True, "Arming denied: airspeed too high (21.0 m/s, FW_AIRSPD_MAX 20 m/s)"),
    ],
)
def test_a_plane_needs_a_valid_airspeed_to_arm(airspeed, fresh, reason):
    clock = plane_clock()
    clock.airspeed, clock.airspeed_fresh = airspeed, fresh
    clock.step(0.1)  # the pre-arm checks run at 10 Hz
    ack = clock.send(C.arm_command())
    assert (ack.result, ack.reason) == (ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED, reason)
    assert not clock.status.pre_flight_checks_pass
    clock.airspeed, clock.airspeed_fresh = 19.5, True
    clock.step(0.1)
    assert clock.status.pre_flight_checks_pass and clock.send(C.arm_command()).result == ACCEPTED


def test_without_an_airspeed_sensor_the_check_is_skipped_and_a_multicopter_never_has_it():
    clock = plane_clock(SYS_HAS_NUM_ASPD=0)
    clock.airspeed_fresh = False
    clock.step()
    assert clock.send(C.arm_command()).result == ACCEPTED
    multicopter = make_clock()
    multicopter.step()
    assert multicopter.send(C.arm_command()).result == ACCEPTED


def test_a_plane_holds_and_returns_on_the_relaxed_local_position_a_multicopter_cannot():
    # A position without a velocity estimate: PX4's fixed-wing Hold/Mission/Return need only the relaxed one.
    plane, multicopter = flying_plane(), make_clock()
    for clock in (plane, multicopter):
        clock.overrides = {"local_position": local_position(clock.t + clock.period, v_xy_valid=False)}
        clock.step()
    assert plane.commander.can_run(NS.NAVIGATION_STATE_AUTO_LOITER)
    assert plane.commander.can_run(NS.NAVIGATION_STATE_AUTO_RTL)
    assert not multicopter.commander.can_run(NS.NAVIGATION_STATE_AUTO_LOITER)


def test_a_plane_takes_off_without_a_horizontal_position():
    # PX4: only a rotary-wing takeoff needs the local position; a runway takeoff needs the altitude.
    plane, multicopter = plane_clock(), make_clock()
    for clock in (plane, multicopter):
        clock.overrides = {"local_position": local_position(clock.t + clock.period, xy_valid=False, v_xy_valid=False)}
        clock.step()
    assert plane.commander.can_run(NS.NAVIGATION_STATE_AUTO_TAKEOFF)
    assert not multicopter.commander.can_run(NS.NAVIGATION_STATE_AUTO_TAKEOFF)


def test_losing_the_position_estimate_in_flight_descends():
    clock = flying_plane()
    clock.overrides = {"local_position": None}
    clock.keep_alive(0.1)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_DESCEND
    assert clock.last.failsafe_action == "descend"


def test_a_data_link_loss_returns_as_on_a_multicopter():
    clock = flying_plane(NAV_DLL_ACT=2)
    clock.overrides = {"last_gcs_heartbeat_us": clock.t}
    clock.keep_alive(9.9)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    clock.keep_alive(0.2)  # COM_DL_LOSS_T 10 s
    assert (clock.last.failsafe_action, clock.last.failsafe_cause) == ("rtl", "gcs_connection_loss")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL


def test_a_manual_control_loss_returns_as_on_a_multicopter():
    clock = flying_plane(sticks=True)
    clock.sticks = False  # the last sticks were now
    clock.overrides = {"last_manual_control_us": clock.t, "manual_control_valid": True}
    clock.keep_alive(0.6)  # COM_RC_LOSS_T 0.5 s, then NAV_RCL_ACT 2
    assert (clock.last.failsafe_action, clock.last.failsafe_cause) == ("rtl", "manual_control_loss")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL


def test_landing_is_complete_when_the_land_detector_says_landed_then_it_disarms():
    clock = flying_plane()
    assert clock.send(C.land_command()).result == ACCEPTED
    clock.fly_to((300.0, 0.0, -5.0))
    clock.step(5.0)
    assert clock.status.arming_state == NS.ARMING_STATE_ARMED  # flying: no disarm however long
    clock.position, clock.landed = (320.0, 0.0, 0.0), True
    clock.step(1.99)
    assert clock.status.arming_state == NS.ARMING_STATE_ARMED
    clock.step(0.02)  # COM_DISARM_LAND 2 s after the touchdown
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED
    assert "Disarmed (auto_disarm_land)" in clock.events


def test_an_infinite_airspeed_from_the_bus_is_an_invalid_one():
    clock = plane_clock()
    clock.airspeed = math.inf
    clock.step(0.1)
    assert clock.send(C.arm_command()).reason == "Arming denied: airspeed invalid"
    assert not clock.status.pre_flight_checks_pass
