import pytest

from stack.commander import commands as C
from stack.commander.modes import (
    MODES,
    VALID_NAV_STATES_MASK,
    control_mode,
    nav_state_from_base_mode,
    nav_state_from_custom_mode,
    nav_state_from_name,
)
from stack.msg.system import VehicleControlMode
from stack.msg.system import VehicleStatus as NS

FLAG_FIELDS = [f for f in VehicleControlMode.__struct_fields__ if f.startswith("flag_") and f != "flag_armed"]

STAB = {"manual", "attitude", "rates", "allocation"}
AUTO = {"auto", "position", "velocity", "altitude", "climb_rate", "attitude", "rates", "allocation", "mc_position"}

# PX4 ModeUtil/control_mode.cpp for a rotary-wing vehicle, plus the older PX4's rattitude.
EXPECTED_FLAGS = {
    NS.NAVIGATION_STATE_MANUAL: STAB,
    NS.NAVIGATION_STATE_STAB: STAB,
    NS.NAVIGATION_STATE_ACRO: {"manual", "rates", "allocation"},
    NS.NAVIGATION_STATE_RATTITUDE: STAB | {"rattitude"},
    NS.NAVIGATION_STATE_EXTERNAL1: STAB | {"rpyt"},  # the RotorS interface
    NS.NAVIGATION_STATE_ALTCTL: STAB | {"altitude", "climb_rate", "mc_position"},
    NS.NAVIGATION_STATE_POSCTL: STAB | {"altitude", "climb_rate", "position", "velocity", "mc_position"},
    NS.NAVIGATION_STATE_AUTO_MISSION: AUTO,
    NS.NAVIGATION_STATE_AUTO_LOITER: AUTO,
    NS.NAVIGATION_STATE_AUTO_RTL: AUTO,
    NS.NAVIGATION_STATE_AUTO_TAKEOFF: AUTO,
    NS.NAVIGATION_STATE_AUTO_LAND: AUTO,
    # Offboard: attitude control by default; the commander module refines it from offboard_control_mode.
    NS.NAVIGATION_STATE_OFFBOARD: {"offboard", "attitude", "rates", "allocation"},
    NS.NAVIGATION_STATE_DESCEND: {"auto", "attitude", "rates", "climb_rate", "allocation", "mc_position"},
    NS.NAVIGATION_STATE_TERMINATION: {"termination"},
}


def _short(field: str) -> str:
    if field == "flag_multicopter_position_control_enabled":
        return "mc_position"
    return field.removeprefix("flag_control_").removesuffix("_enabled")


@pytest.mark.parametrize("nav_state", sorted(EXPECTED_FLAGS))
@pytest.mark.parametrize("armed", [False, True])
def test_control_mode_flags_of_every_mode(nav_state, armed):
    msg = control_mode(nav_state, armed)
    assert {_short(f) for f in FLAG_FIELDS if getattr(msg, f)} == EXPECTED_FLAGS[nav_state]
    assert msg.flag_armed is armed
    assert msg.source_id == nav_state


def test_every_mode_is_in_the_table():
    assert set(EXPECTED_FLAGS) == set(MODES)
    assert sum(1 << s for s in EXPECTED_FLAGS) == VALID_NAV_STATES_MASK


@pytest.mark.parametrize(
    ("main", "sub", "nav_state"),
    [
        (1, 0, NS.NAVIGATION_STATE_MANUAL),
        (2, 0, NS.NAVIGATION_STATE_ALTCTL),
        (3, 0, NS.NAVIGATION_STATE_POSCTL),
        (4, 0, NS.NAVIGATION_STATE_AUTO_MISSION),
        (4, 2, NS.NAVIGATION_STATE_AUTO_TAKEOFF),
        (4, 3, NS.NAVIGATION_STATE_AUTO_LOITER),
        (4, 4, NS.NAVIGATION_STATE_AUTO_MISSION),
        (4, 5, NS.NAVIGATION_STATE_AUTO_RTL),
        (4, 6, NS.NAVIGATION_STATE_AUTO_LAND),
        (5, 0, NS.NAVIGATION_STATE_ACRO),
        (7, 0, NS.NAVIGATION_STATE_STAB),
        (8, 0, NS.NAVIGATION_STATE_RATTITUDE),
        (7, 3, NS.NAVIGATION_STATE_STAB),  # PX4 ignores the sub mode of most main modes
        (3, 1, None),  # Position's Orbit sub mode: not supported
        (6, 0, NS.NAVIGATION_STATE_OFFBOARD),
        (4, 9, None),  # precision land: not supported
        (4, 11, NS.NAVIGATION_STATE_EXTERNAL1),  # the RotorS interface in PX4's first external mode slot
        (4, 12, None),
        (10, 0, None),  # termination is not selectable
        (42, 0, None),
    ],
)
def test_px4_custom_mode_decoding(main, sub, nav_state):
    assert nav_state_from_custom_mode(main, sub) == nav_state


def test_base_mode_decoding():
    assert nav_state_from_base_mode(4) == NS.NAVIGATION_STATE_AUTO_MISSION
    assert nav_state_from_base_mode(64 | 8) == NS.NAVIGATION_STATE_POSCTL
    assert nav_state_from_base_mode(64 | 16) == NS.NAVIGATION_STATE_STAB
    assert nav_state_from_base_mode(64) == NS.NAVIGATION_STATE_MANUAL
    assert nav_state_from_base_mode(0) is None


def test_names_and_aliases():
    assert nav_state_from_name("posctl") == NS.NAVIGATION_STATE_POSCTL
    assert nav_state_from_name("Position") == NS.NAVIGATION_STATE_POSCTL
    assert nav_state_from_name("auto:loiter") == nav_state_from_name("hold") == NS.NAVIGATION_STATE_AUTO_LOITER
    assert nav_state_from_name("rattitude") == NS.NAVIGATION_STATE_RATTITUDE
    assert nav_state_from_name("rotors") == nav_state_from_name("RotorS") == NS.NAVIGATION_STATE_EXTERNAL1
    with pytest.raises(ValueError, match="unknown mode 'descend'"):
        nav_state_from_name("descend")


@pytest.mark.parametrize("nav_state", [s for s, m in MODES.items() if m.user_selectable])
def test_set_mode_command_round_trip(nav_state):
    cmd = C.set_mode_command(MODES[nav_state].cli_name)
    assert cmd.param1 == 1.0
    assert nav_state_from_custom_mode(round(cmd.param2), round(cmd.param3)) == nav_state
