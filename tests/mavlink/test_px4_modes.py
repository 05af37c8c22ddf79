"""PX4's custom mode encoding (px4_custom_mode.h) and its mapping to the stack's nav states."""

import pytest

from stack.commander.modes import MODES
from stack.mavlink import px4_modes as P
from stack.mavlink.px4_modes import Px4Mode
from stack.msg.system import VehicleStatus as NS


@pytest.mark.parametrize(
    ("mode", "custom_mode", "text"),
    [
        (Px4Mode.MANUAL, 0x0001_0000, "MANUAL"),
        (Px4Mode.ALTCTL, 0x0002_0000, "ALTCTL"),
        (Px4Mode.POSCTL, 0x0003_0000, "POSCTL"),
        (Px4Mode.POSCTL_ORBIT, 0x0103_0000, "POSCTL.ORBIT"),
        (Px4Mode.AUTO_READY, 0x0104_0000, "AUTO.READY"),
        (Px4Mode.AUTO_TAKEOFF, 0x0204_0000, "AUTO.TAKEOFF"),
        (Px4Mode.AUTO_LOITER, 0x0304_0000, "AUTO.LOITER"),
        (Px4Mode.AUTO_MISSION, 0x0404_0000, "AUTO.MISSION"),
        (Px4Mode.AUTO_RTL, 0x0504_0000, "AUTO.RTL"),
        (Px4Mode.AUTO_LAND, 0x0604_0000, "AUTO.LAND"),
        (Px4Mode.AUTO_PRECLAND, 0x0904_0000, "AUTO.PRECLAND"),
        (Px4Mode.ACRO, 0x0005_0000, "ACRO"),
        (Px4Mode.OFFBOARD, 0x0006_0000, "OFFBOARD"),
        (Px4Mode.STABILIZED, 0x0007_0000, "STABILIZED"),
        (Px4Mode.TERMINATION, 0x000A_0000, "TERMINATION"),
    ],
)
def test_encoding_matches_the_px4_union(mode, custom_mode, text):
    # main mode in bits 16-23, sub mode in bits 24-31, as the px4_custom_mode union lays them out
    assert P.encode(mode) == custom_mode
    assert P.decode(custom_mode) is mode
    assert P.name(mode) == text
    assert P.describe(custom_mode) == text


def test_every_mode_round_trips():
    for mode in Px4Mode:
        assert P.decode(P.encode(mode)) is mode


def test_decode_ignores_the_reserved_bits_and_the_sub_mode_of_plain_main_modes():
    assert P.decode(P.encode(Px4Mode.OFFBOARD) | 0xBEEF) is Px4Mode.OFFBOARD
    assert P.decode((3 << 24) | (7 << 16)) is Px4Mode.STABILIZED


@pytest.mark.parametrize("custom_mode", [0, 0x0004_0000, 0x0704_0000, 0x2A_0000, 0x0903_0000, 0xFFFF_FFFF])
def test_undefined_values_decode_to_none(custom_mode):
    assert P.decode(custom_mode) is None
    assert P.describe(custom_mode).startswith("main ")


def test_nav_state_mapping_follows_get_px4_custom_mode():
    assert P.from_nav_state(NS.NAVIGATION_STATE_OFFBOARD) is Px4Mode.OFFBOARD
    assert P.from_nav_state(NS.NAVIGATION_STATE_AUTO_LOITER) is Px4Mode.AUTO_LOITER
    assert P.from_nav_state(NS.NAVIGATION_STATE_DESCEND) is Px4Mode.AUTO_LAND
    assert P.to_nav_state(Px4Mode.AUTO_LAND) == NS.NAVIGATION_STATE_AUTO_LAND
    assert P.to_nav_state(Px4Mode.AUTO_PRECLAND) is None
    assert P.from_nav_state(99) is None
    for mode in P.NAV_STATE_MODE.values():
        back = P.to_nav_state(mode)
        assert back is not None and P.from_nav_state(back) is mode


def test_every_stack_mode_has_its_px4_mode():
    for nav_state, info in MODES.items():
        mode = P.from_nav_state(nav_state)
        assert mode is not None
        assert info.custom_mode == (mode.main_mode, mode.sub_mode)
