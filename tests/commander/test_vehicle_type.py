"""MAV_TYPE, the one definition of the vehicle's type: the commander's vehicle_type, the modes' control flags,
and the HEARTBEAT every ground-station link sends."""

from types import SimpleNamespace

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from stack.commander import commands as C
from stack.commander.control_chain import CHAIN, FW_CHAIN
from stack.commander.modes import VALID_NAV_STATES_MASK, control_mode, vehicle_type_from_mav_type
from stack.commander.state_machine import Commander
from stack.mavlink.module import MavlinkModule
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import make_clock

FW = NS.VEHICLE_TYPE_FIXED_WING
RW = NS.VEHICLE_TYPE_ROTARY_WING


@pytest.mark.parametrize(
    ("mav_type", "vehicle_type"), [(1, FW), (2, RW), (3, RW), (4, RW), (13, RW), (14, RW), (15, RW)]
)
def test_vehicle_type_from_mav_type(mav_type, vehicle_type):
    assert vehicle_type_from_mav_type(mav_type) == vehicle_type
    status = make_clock(MAV_TYPE=mav_type).status
    assert (status.vehicle_type, status.system_type) == (vehicle_type, mav_type)


def test_the_default_is_a_quadrotor_with_every_mode():
    status = Commander().update(1_000_000, make_clock().inputs()).vehicle_status
    assert (status.vehicle_type, status.system_type) == (RW, 2)
    assert status.valid_nav_states_mask == VALID_NAV_STATES_MASK


def test_a_plane_has_neither_rattitude_nor_the_rotors_mode():
    status = make_clock(MAV_TYPE=1).status
    missing = (1 << NS.NAVIGATION_STATE_RATTITUDE) | (1 << NS.NAVIGATION_STATE_EXTERNAL1)
    assert status.valid_nav_states_mask == VALID_NAV_STATES_MASK & ~missing
    assert not status.can_set_nav_states_mask & missing
    assert status.can_set_nav_states_mask & (1 << NS.NAVIGATION_STATE_AUTO_LOITER)


def test_a_change_of_mav_type_waits_for_the_disarm():
    clock = make_clock()
    clock.step()
    clock.send(C.arm_command())
    clock.commander.set_params({"COM_FAIL_ACT_T": 0.0, "MAV_TYPE": 1})
    assert clock.step().vehicle_status.vehicle_type == RW
    assert clock.commander.chain.chain is CHAIN
    clock.send(C.disarm_command())
    status = clock.step().vehicle_status
    assert (status.vehicle_type, status.system_type) == (FW, 1)
    assert clock.commander.chain.chain is FW_CHAIN


def _flags(nav_state: int, vehicle_type: int) -> set[str]:
    msg = control_mode(nav_state, True, vehicle_type)
    return {f.removeprefix("flag_") for f in msg.__struct_fields__ if f.startswith("flag_") and getattr(msg, f)}


def test_a_planes_manual_mode_is_direct_and_it_has_no_multicopter_position_control():
    # PX4 ModeUtil/control_mode.cpp: stabilization_required() only for a rotary wing, and
    # flag_multicopter_position_control_enabled only for a rotary wing.
    assert _flags(NS.NAVIGATION_STATE_MANUAL, FW) == {"armed", "control_manual_enabled", "control_allocation_enabled"}
    assert "control_attitude_enabled" in _flags(NS.NAVIGATION_STATE_MANUAL, RW)
    assert _flags(NS.NAVIGATION_STATE_POSCTL, FW) == _flags(NS.NAVIGATION_STATE_POSCTL, RW) - {
        "multicopter_position_control_enabled"
    }
    assert _flags(NS.NAVIGATION_STATE_STAB, FW) == _flags(NS.NAVIGATION_STATE_STAB, RW)
    for nav_state in (NS.NAVIGATION_STATE_AUTO_LOITER, NS.NAVIGATION_STATE_DESCEND, NS.NAVIGATION_STATE_ALTCTL):
        assert "multicopter_position_control_enabled" not in _flags(nav_state, FW)
    assert make_clock(MAV_TYPE=1).last.vehicle_control_mode == control_mode(NS.NAVIGATION_STATE_MANUAL, False, FW)


def _link(mav_type: int, status: NS | None) -> SimpleNamespace:
    """What a ``mavlink`` module's heartbeat reads: its view of vehicle_status and its parameters."""
    return SimpleNamespace(view=SimpleNamespace(status=status), params={"MAV_TYPE": mav_type})


def test_the_heartbeats_mav_type_follows_the_parameter():
    assert "mav_type" not in {arg.name for arg in MavlinkModule.ARGS}
    assert "MAV_TYPE" in {p.name for p in MavlinkModule.PARAMS}
    link = _link(2, None)
    assert MavlinkModule._heartbeat(link)["type"] == mavlink2.MAV_TYPE_QUADROTOR
    link.params["MAV_TYPE"] = 1  # a parameter set: the next heartbeat says so
    assert MavlinkModule._heartbeat(link)["type"] == mavlink2.MAV_TYPE_FIXED_WING
    status = make_clock(MAV_TYPE=13).status
    heartbeat = MavlinkModule._heartbeat(_link(13, status))
    assert heartbeat["type"] == mavlink2.MAV_TYPE_HEXAROTOR == status.system_type
    assert heartbeat["system_status"] == mavlink2.MAV_STATE_STANDBY
