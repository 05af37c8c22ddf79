"""HEARTBEAT and AUTOPILOT_VERSION as PX4 sends them."""

import pytest
from pymavlink.dialects.v20 import common as M

from stack.commander.modes import MODES
from stack.mavlink import px4_modes
from stack.mavlink.identity import CAPABILITIES, autopilot_version, heartbeat, software_version
from stack.mavlink.inspect import firmware
from stack.msg.system import VehicleStatus as NS
from stack.record.provenance import git_commit

STATUS = NS(arming_state=NS.ARMING_STATE_DISARMED, nav_state=NS.NAVIGATION_STATE_POSCTL)


@pytest.mark.parametrize("nav_state", sorted(px4_modes.NAV_STATE_MODE))
def test_every_mode_of_the_commander_is_px4s_custom_mode(nav_state):
    hb = heartbeat(NS(nav_state=nav_state), M.MAV_TYPE_QUADROTOR)
    assert px4_modes.decode(hb["custom_mode"]) is px4_modes.from_nav_state(nav_state)
    assert hb["base_mode"] & M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert hb["autopilot"] == M.MAV_AUTOPILOT_PX4 and hb["type"] == M.MAV_TYPE_QUADROTOR


def test_the_commanders_modes_all_have_a_px4_encoding():
    assert set(MODES) <= set(px4_modes.NAV_STATE_MODE)


def test_armed_and_mode_flags_follow_px4():
    hb = heartbeat(STATUS, 13)
    assert hb["type"] == 13 and hb["system_status"] == M.MAV_STATE_STANDBY
    assert not hb["base_mode"] & M.MAV_MODE_FLAG_SAFETY_ARMED
    assert hb["base_mode"] & M.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED and hb["base_mode"] & M.MAV_MODE_FLAG_GUIDED_ENABLED
    armed = heartbeat(NS(arming_state=NS.ARMING_STATE_ARMED, nav_state=NS.NAVIGATION_STATE_AUTO_MISSION), 2)
    assert armed["base_mode"] & M.MAV_MODE_FLAG_SAFETY_ARMED and armed["base_mode"] & M.MAV_MODE_FLAG_AUTO_ENABLED
    assert armed["system_status"] == M.MAV_STATE_ACTIVE
    assert armed["custom_mode"] == 4 << 16 | 4 << 24


def test_before_the_commander_speaks_the_vehicle_is_uninitialised():
    hb = heartbeat(None, 2)
    assert (hb["system_status"], hb["custom_mode"]) == (M.MAV_STATE_UNINIT, 0)


def test_capabilities_say_what_is_implemented_and_nothing_more():
    for bit in (
        M.MAV_PROTOCOL_CAPABILITY_MISSION_INT,
        M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT,
        M.MAV_PROTOCOL_CAPABILITY_MAVLINK2,
        M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE,
    ):
        assert CAPABILITIES & bit
    for bit in (
        M.MAV_PROTOCOL_CAPABILITY_FTP,
        M.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE,
        M.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY,
        M.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT,
        M.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST,
    ):
        assert not CAPABILITIES & bit
    version = autopilot_version("v1", 1)
    assert version.capabilities == CAPABILITIES
    assert version.uid == autopilot_version("v1", 1).uid != autopilot_version("v1", 2).uid
    mav = M.MAVLink(None, 1, 1)
    assert mav.decode(bytearray(version.pack(mav))).capabilities == CAPABILITIES
    # The git hash in PX4's byte order, which `stack mavlink inspect` (and QGroundControl) read back as written.
    commit = git_commit()
    assert commit and firmware(version)["git_hash"] == commit[:16]


def test_software_version_packs_major_minor_patch_and_type():
    assert software_version("1.15.2") == 1 << 24 | 15 << 16 | 2 << 8 | M.FIRMWARE_VERSION_TYPE_DEV
    assert software_version("0.1.0.dev3") == 1 << 16
