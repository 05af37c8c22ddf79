import math

import pytest

from stack.commander import commands as C
from stack.commander.state_machine import VEHICLE_CMD_DO_REPOSITION_LOCAL, VEHICLE_CMD_SET_NAV_STATE
from stack.mathlib.geo import MapProjection
from stack.msg.system import VehicleCommand, command_label
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import REF, make_clock

CMD = VehicleCommand
NAN = math.nan
INF = math.inf


def _snapshot(out):
    """The state a command could change, from one cycle's outputs."""
    s = out.vehicle_status
    return (s.arming_state, s.armed_time, s.nav_state, s.nav_state_user_intention, out.home, out.navigation)


def _flying_clock(**params):
    clock = make_clock(GF_MAX_HOR_DIST=100.0, GF_MAX_VER_DIST=50.0, **params)
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -10.0))
    return clock


BAD_COMMANDS = [
    (CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=NAN), 1, "param1 must be 1 (arm) or 0 (disarm)"),
    (CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=2.0), 1, "got 2"),
    (CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=-1.0), 1, "got -1"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=NAN, param2=3.0), 1, "base mode"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=1.0, param2=NAN), 2, "custom main mode"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=1.0, param2=99.0, param3=0.0), 2, "unknown or unsupported"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=1.0, param2=4.0, param3=INF), 3, "sub mode"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=0.0), 1, "names no flight mode"),
    (CMD(command=VEHICLE_CMD_SET_NAV_STATE, param1=99.0), 1, "unknown mode id 99"),
    (CMD(command=VEHICLE_CMD_SET_NAV_STATE, param1=2.5), 1, "unknown mode id 2.5"),
    (CMD(command=VEHICLE_CMD_SET_NAV_STATE, param1=float(NS.NAVIGATION_STATE_DESCEND)), 1, "Unsupported mode"),
    (C.takeoff_command(-5.0), 7, "-5.0 m above home is outside MIS_TAKEOFF_ALT's range (0, 80] m"),
    (C.takeoff_command(0.0), 7, "outside MIS_TAKEOFF_ALT's range"),
    (C.takeoff_command(1e9), 7, "1000000000.0 m above home is outside MIS_TAKEOFF_ALT's range (0, 80] m"),
    (C.takeoff_command(80.0), 7, "beyond GF_MAX_VER_DIST 50 m"),
    (C.takeoff_command(INF), 7, "must be finite"),
    (C.takeoff_command(400.0, relative=False), 7, "-89.4 m above home is outside MIS_TAKEOFF_ALT's range"),
    (C.takeoff_command(5.0, yaw_deg=INF), 4, "yaw"),
    (C.takeoff_command(5.0, yaw_deg=1e300), 4, "yaw (param4) must be within ±360° or NaN"),
    (CMD(command=CMD.VEHICLE_CMD_NAV_TAKEOFF, param2=INF, param7=5.0), 2, "Takeoff: param2 must be finite or NaN"),
    (C.goto_local_command(500.0, 0.0, -10.0), 5, "outside the geofence"),
    (C.goto_local_command(0.0, 0.0, -70.0), 5, "beyond GF_MAX_VER_DIST"),
    (C.goto_local_command(INF, 0.0, -10.0), 5, "param5 must be finite or NaN"),
    (C.goto_local_command(1e9, 0.0, -5.0), 5, "1000000000.0 m from home, beyond MIS_DIST_1WP 900 m"),
    (C.goto_local_command(0.0, 0.0, 1e9), 7, "below NAV_MC_ALT_RAD 0.8 m (it would fly into the ground)"),
    (C.goto_local_command(0.0, 0.0, -0.5), 7, "0.5 m above home, below NAV_MC_ALT_RAD"),
    (C.goto_local_command(5.0, 0.0, -5.0, yaw_deg=-INF), 4, "yaw (param4) must be within ±360° or NaN"),
    (CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=0.0, param2=INF), 2, "Arm/disarm: param2 must be"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=INF, param2=1.0), 1, "base mode (param1) must be 0–255"),
    (CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=1.0, param2=1e300), 2, "unknown or unsupported"),
    (C.goto_global_command(95.0, 8.5, 500.0), 5, "latitude 95 is outside"),
    (C.goto_global_command(47.4, NAN, 500.0), 5, "give both latitude"),
    (C.goto_global_command(47.4, 200.0, 500.0), 6, "longitude 200"),
    (CMD(command=CMD.VEHICLE_CMD_MISSION_START, param1=0.0), 0, "no valid mission"),
]


@pytest.mark.parametrize(("cmd", "param", "reason"), BAD_COMMANDS)
def test_nan_or_out_of_range_commands_are_denied_with_a_reason_and_change_nothing(cmd, param, reason):
    clock = _flying_clock()
    before = _snapshot(clock.step())
    ack = clock.send(cmd)
    assert ack.result == ACK.VEHICLE_CMD_RESULT_DENIED
    assert reason in ack.reason
    assert ack.result_param2 == param
    assert ack.command == cmd.command
    out = clock.step()
    assert _snapshot(out) == before
    assert ack.reason in out.events


def test_mission_start_item_out_of_range():
    clock = make_clock()
    clock.overrides = {"mission_count": 3}
    clock.step()
    for first in (NAN, 3.0, -2.0, 1.5):
        ack = clock.send(_mission_start(first))
        assert ack.result == ACK.VEHICLE_CMD_RESULT_DENIED
        assert "first item (param1) must be −1…2" in ack.reason
    assert not clock.commander.armed


def _mission_start(first: float) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_MISSION_START, param1=first)


@pytest.mark.parametrize("command", [CMD.VEHICLE_CMD_NAV_WAYPOINT, 241, CMD.VEHICLE_CMD_DO_FLIGHTTERMINATION, 31000])
def test_unknown_commands_are_unsupported(command):
    clock = make_clock()
    before = _snapshot(clock.step())
    ack = clock.send(CMD(command=command, param1=1.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_UNSUPPORTED
    assert ack.reason == f"Unsupported command {command_label(command)}"
    if command == CMD.VEHICLE_CMD_NAV_WAYPOINT:
        assert ack.reason == "Unsupported command NAV_WAYPOINT (16)"  # by MAVLink's name where it has one
    assert _snapshot(clock.step()) == before


def test_ack_addresses_the_sender():
    clock = make_clock()
    ack = clock.send(CMD(command=CMD.VEHICLE_CMD_NAV_LAND, source_system=42, source_component=190))
    assert (ack.target_system, ack.target_component, ack.from_external) == (42, 190, False)


def test_mode_changes_by_px4_encoding_and_by_nav_state():
    clock = make_clock()
    assert clock.send(C.set_mode_command("altctl")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_ALTCTL
    qgc = CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=1.0, param2=4.0, param3=3.0)
    assert clock.send(qgc).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert clock.send(C.set_nav_state_command(NS.NAVIGATION_STATE_ACRO)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.nav_state == out.vehicle_status.nav_state_user_intention == NS.NAVIGATION_STATE_ACRO
    assert out.vehicle_status.nav_state_timestamp == clock.t - clock.period


def test_mode_refusals_are_temporary_and_explained():
    clock = make_clock()
    ack = clock.send(C.set_mode_command("mission"))
    assert (ack.result, ack.reason) == (
        ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED,
        "Switching to Mission is currently not possible: no valid mission",
    )
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -5.0))
    ack = clock.send(C.takeoff_command(10.0))
    assert ack.reason == "Switching to Takeoff is currently not possible: already flying"
    clock.overrides = {"local_position": None}
    clock.step()
    clock.sticks = True
    clock.step()
    ack = clock.send(C.set_mode_command("posctl"))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Switching to Position is currently not possible: requires a local position estimate"
    assert clock.send(C.set_mode_command("stabilized")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_takeoff_arms_and_climbs_to_the_relative_altitude_then_holds():
    clock = make_clock()
    ack = clock.send(C.takeoff_command(5.0, yaw_deg=90.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    assert out.navigation.takeoff_altitude == 5.0
    assert out.navigation.takeoff_yaw == pytest.approx(math.pi / 2)
    assert clock.fly_to((0.0, 0.0, -3.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
    out = clock.fly_to((0.0, 0.0, -4.3))
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert out.vehicle_status.nav_state_user_intention == NS.NAVIGATION_STATE_AUTO_LOITER
    assert "Takeoff complete, switching to Hold" in out.events
    assert out.vehicle_status.takeoff_time > out.vehicle_status.armed_time


def test_takeoff_amsl_and_default_altitudes():
    clock = make_clock()
    ack = clock.send(C.takeoff_command(REF[2] + 12.0, relative=False))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().navigation.takeoff_altitude == pytest.approx(12.0)
    other = make_clock(MIS_TAKEOFF_ALT=4.0)
    assert other.send(C.takeoff_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert other.step().navigation.takeoff_altitude == 4.0


def test_takeoff_refused_by_prearm_checks_changes_nothing():
    clock = make_clock()
    clock.overrides = {"attitude_timestamp_us": 0}
    before = _snapshot(clock.step())
    ack = clock.send(C.takeoff_command(5.0))
    assert (ack.result, ack.reason) == (
        ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED,
        "Arming denied: attitude estimate invalid",
    )
    assert _snapshot(clock.step()) == before


def test_takeoff_then_mission_when_com_takeoff_act_is_1():
    clock = make_clock(COM_TAKEOFF_ACT=1)
    clock.overrides = {"mission_count": 4}
    clock.send(C.takeoff_command(5.0))
    assert clock.fly_to((0.0, 0.0, -5.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION


def test_goto_local_switches_to_hold_with_the_target():
    clock = _flying_clock()
    ack = clock.send(C.goto_local_command(20.0, NAN, -15.0, yaw_deg=180.0, speed=3.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    north, east, down, yaw = out.navigation.reposition
    assert (north, east, down) == (20.0, 0.0, -15.0)
    assert yaw == pytest.approx(math.pi)
    assert out.navigation.reposition_speed == 3.0
    assert out.navigation.reposition_counter == 1


def test_goto_global_is_converted_to_the_local_frame():
    clock = _flying_clock()
    lat, lon = MapProjection(REF[0], REF[1]).reproject(30.0, -40.0)
    ack = clock.send(C.goto_global_command(lat, lon, REF[2] + 20.0))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    north, east, down, yaw = clock.step().navigation.reposition
    assert (north, east, down) == pytest.approx((30.0, -40.0, -20.0), abs=1e-6)
    assert math.isnan(yaw)


def test_goto_refused_on_the_ground():
    clock = make_clock()
    ack = clock.send(C.goto_local_command(5.0, 0.0, -5.0))
    assert (ack.result, ack.reason) == (
        ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED,
        "Reposition denied: the vehicle is not flying",
    )
    assert clock.step().navigation.reposition is None


def test_local_reposition_command_id_is_the_extension():
    assert C.goto_local_command(1.0, 2.0, 3.0).command == VEHICLE_CMD_DO_REPOSITION_LOCAL


def test_mission_start_arms_in_mission_mode():
    clock = make_clock()
    clock.overrides = {"mission_count": 5}
    clock.step()
    ack = clock.send(C.mission_start_command(2))
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    assert out.vehicle_status.latest_arming_reason == 5
    assert (out.navigation.mission_start_index, out.navigation.mission_start_counter) == (2, 1)


def test_status_is_marked_changed_only_when_it_changes():
    clock = make_clock()
    clock.step()
    assert not clock.step().changed
    clock.send(C.set_mode_command("hold"))
    assert clock.step().changed
    assert not clock.step().changed
