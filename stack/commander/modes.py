"""The flight modes: names, what each needs to run, the loops it enables, and its MAVLink encoding.

One table, :data:`MODES`, keyed by PX4's ``vehicle_status.nav_state`` numbers, holds for each mode

* ``requirements`` — PX4 ``ModeUtil/mode_requirements.cpp`` for a rotary-wing vehicle: the estimates and
  data the mode cannot run without, and whether it forbids arming (Return, Land, Descend, Termination);
  ``fixed_wing_requirements`` where a fixed-wing vehicle's differ (Mission, Hold and Return need only the
  relaxed local position, Takeoff no horizontal position at all: a runway takeoff holds its heading);
* ``control_flags`` — the ``vehicle_control_mode`` flags PX4 ``ModeUtil/control_mode.cpp`` sets for it
  (rotary wing: Manual is stabilised like Stabilized; fixed wing: Manual is direct, no attitude or rate loop,
  and ``flag_multicopter_position_control_enabled`` is never set). ``flag_control_allocation_enabled`` is set in every
  mode but Termination, as PX4's own modes leave the allocator on. Rattitude is the older PX4's mode (removed
  from PX4 in 2021): manual, attitude and rates plus ``flag_control_rattitude_enabled``;
* RotorS is the stack's own mode in PX4's first external mode slot (EXTERNAL1, as a ROS 2 mode registers): the
  sticks map to roll, pitch, yaw rate and thrust in newtons as RotorS' ``rotors_joy_interface`` maps them
  (``flag_control_rpyt_enabled``), flown by the RotorS controller or by PX4's attitude loop;
* ``fixed_wing`` — whether a plane has the mode: the RotorS interface and Rattitude are multicopter modes
  (PX4's fixed-wing attitude controller has no rattitude here), refused on a plane with that reason;
* ``custom_mode`` — the PX4 custom main/sub mode (``px4_custom_mode.h``, from :mod:`stack.mavlink.px4_modes`)
  QGroundControl and MAVLink send in ``MAV_CMD_DO_SET_MODE`` param2/param3 (with param1 =
  MAV_MODE_FLAG_CUSTOM_MODE_ENABLED).

The vehicle type (``vehicle_status.vehicle_type``) comes from PX4's MAV_TYPE parameter, as PX4's commander
derives it (``commander_helper.cpp``): 1 is a fixed-wing vehicle, the rotor types a rotary-wing one.

The manual-control (RC) requirement is not one of the run requirements: armed, a switch to a mode that has it
is refused without manual control input (the commander's mode change, as PX4's ``UserModeIntention::change``),
and the loss of that input in flight is a failsafe of its own (NAV_RCL_ACT, :mod:`stack.commander.failsafe`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntFlag

from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import MainMode
from stack.msg.system import VehicleControlMode, VehicleStatus

NS = VehicleStatus
ROTARY_WING = NS.VEHICLE_TYPE_ROTARY_WING
FIXED_WING = NS.VEHICLE_TYPE_FIXED_WING
MAV_TYPE_FIXED_WING = 1


def vehicle_type_from_mav_type(mav_type: int) -> int:
    """``vehicle_status.vehicle_type`` for a MAV_TYPE (PX4 ``is_fixed_wing``/``is_rotary_wing``): a fixed-wing
    vehicle for MAV_TYPE_FIXED_WING, else rotary wing (the MAV_TYPE parameter admits no other kind)."""
    return FIXED_WING if mav_type == MAV_TYPE_FIXED_WING else ROTARY_WING


class Requirement(IntFlag):
    """What a mode needs (PX4 ``failsafe_flags.mode_req_*``)."""

    NONE = 0
    ANGULAR_VELOCITY = 1
    ATTITUDE = 2
    LOCAL_POSITION = 4
    LOCAL_POSITION_RELAXED = 8
    LOCAL_ALT = 16
    MISSION = 32
    HOME = 64
    PREVENT_ARMING = 128
    MANUAL_CONTROL = 256


REQUIREMENT_TEXT: dict[Requirement, str] = {
    Requirement.ANGULAR_VELOCITY: "an angular velocity estimate",
    Requirement.ATTITUDE: "a valid attitude estimate",
    Requirement.LOCAL_POSITION: "a valid local position estimate",
    Requirement.LOCAL_POSITION_RELAXED: "a local position estimate",
    Requirement.LOCAL_ALT: "a valid altitude estimate",
    Requirement.MISSION: "a valid mission",
    Requirement.HOME: "a home position",
}
"""How each run requirement reads in a refusal ("... requires <text>")."""

REQUIREMENT_CAUSE: dict[Requirement, str] = {
    Requirement.ANGULAR_VELOCITY: "angular_velocity_invalid",
    Requirement.ATTITUDE: "attitude_invalid",
    Requirement.LOCAL_POSITION: "local_position_invalid",
    Requirement.LOCAL_POSITION_RELAXED: "local_position_invalid",
    Requirement.LOCAL_ALT: "local_altitude_invalid",
    Requirement.MISSION: "mission_invalid",
    Requirement.HOME: "home_position_invalid",
}
"""The failsafe cause name of each failing requirement (PX4 ``failsafe_flags`` names)."""

RUN_REQUIREMENTS = Requirement(
    Requirement.ANGULAR_VELOCITY
    | Requirement.ATTITUDE
    | Requirement.LOCAL_POSITION
    | Requirement.LOCAL_POSITION_RELAXED
    | Requirement.LOCAL_ALT
    | Requirement.MISSION
    | Requirement.HOME
)
"""The requirements checked by "can this mode run" (not arming prevention, not manual control)."""


MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
MAV_MODE_FLAG_AUTO_ENABLED = 4
MAV_MODE_FLAG_GUIDED_ENABLED = 8
MAV_MODE_FLAG_STABILIZE_ENABLED = 16
MAV_MODE_FLAG_MANUAL_INPUT_ENABLED = 64

_MANUAL = "flag_control_manual_enabled"
_AUTO = "flag_control_auto_enabled"
_POSITION = "flag_control_position_enabled"
_VELOCITY = "flag_control_velocity_enabled"
_ALTITUDE = "flag_control_altitude_enabled"
_CLIMB_RATE = "flag_control_climb_rate_enabled"
_ATTITUDE = "flag_control_attitude_enabled"
_RATES = "flag_control_rates_enabled"
_ALLOCATION = "flag_control_allocation_enabled"
_TERMINATION = "flag_control_termination_enabled"
_RATTITUDE = "flag_control_rattitude_enabled"
_RPYT = "flag_control_rpyt_enabled"
_MC_POSITION_CONTROL = "flag_multicopter_position_control_enabled"

_POSITION_LOOPS = frozenset({_ALTITUDE, _CLIMB_RATE, _POSITION, _VELOCITY, "flag_control_acceleration_enabled"})

R = Requirement
_STAB_FLAGS = frozenset({_MANUAL, _ATTITUDE, _RATES, _ALLOCATION})
_AUTO_FLAGS = frozenset({_AUTO, _POSITION, _VELOCITY, _ALTITUDE, _CLIMB_RATE, _ATTITUDE, _RATES, _ALLOCATION})
_AV_ATT = R.ANGULAR_VELOCITY | R.ATTITUDE


@dataclass(frozen=True, slots=True)
class ModeInfo:
    nav_state: int
    name: str
    """PX4's display name ("Position", "Hold", ...)."""
    cli_name: str
    """The name ``commander mode`` takes (PX4's CLI spelling)."""
    requirements: Requirement
    control_flags: frozenset[str]
    user_selectable: bool = True
    """False for the failsafe-only modes (Descend, Termination)."""
    fixed_wing_requirements: Requirement | None = None
    """A fixed-wing vehicle's requirements where they differ from ``requirements``."""
    fixed_wing: bool = True
    """Whether a fixed-wing vehicle has this mode."""

    def requirements_for(self, vehicle_type: int) -> Requirement:
        if vehicle_type == FIXED_WING and self.fixed_wing_requirements is not None:
            return self.fixed_wing_requirements
        return self.requirements

    def available(self, vehicle_type: int) -> bool:
        return self.fixed_wing or vehicle_type != FIXED_WING

    @property
    def custom_mode(self) -> tuple[int, int]:
        """PX4 custom (main, sub) mode (``stack.mavlink.px4_modes``)."""
        mode = px4_modes.NAV_STATE_MODE[self.nav_state]
        return mode.main_mode, mode.sub_mode


MODES: dict[int, ModeInfo] = {
    m.nav_state: m
    for m in (
        ModeInfo(NS.NAVIGATION_STATE_MANUAL, "Manual", "manual", R.MANUAL_CONTROL, _STAB_FLAGS),
        ModeInfo(
            NS.NAVIGATION_STATE_STAB,
            "Stabilized",
            "stabilized",
            _AV_ATT | R.MANUAL_CONTROL,
            _STAB_FLAGS,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_ACRO,
            "Acro",
            "acro",
            R.ANGULAR_VELOCITY | R.MANUAL_CONTROL,
            frozenset({_MANUAL, _RATES, _ALLOCATION}),
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_RATTITUDE,
            "Rattitude",
            "rattitude",
            _AV_ATT | R.MANUAL_CONTROL,
            _STAB_FLAGS | {_RATTITUDE},
            fixed_wing=False,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_EXTERNAL1,
            "RotorS",
            "rotors",
            _AV_ATT | R.MANUAL_CONTROL,
            _STAB_FLAGS | {_RPYT},
            fixed_wing=False,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_ALTCTL,
            "Altitude",
            "altctl",
            _AV_ATT | R.LOCAL_ALT | R.MANUAL_CONTROL,
            _STAB_FLAGS | {_ALTITUDE, _CLIMB_RATE},
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_POSCTL,
            "Position",
            "posctl",
            _AV_ATT | R.LOCAL_ALT | R.LOCAL_POSITION_RELAXED | R.MANUAL_CONTROL,
            _STAB_FLAGS | {_ALTITUDE, _CLIMB_RATE, _POSITION, _VELOCITY},
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_AUTO_MISSION,
            "Mission",
            "auto:mission",
            _AV_ATT | R.LOCAL_POSITION | R.LOCAL_ALT | R.MISSION,
            _AUTO_FLAGS,
            fixed_wing_requirements=_AV_ATT | R.LOCAL_POSITION_RELAXED | R.LOCAL_ALT | R.MISSION,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_AUTO_LOITER,
            "Hold",
            "auto:loiter",
            _AV_ATT | R.LOCAL_POSITION | R.LOCAL_ALT,
            _AUTO_FLAGS,
            fixed_wing_requirements=_AV_ATT | R.LOCAL_POSITION_RELAXED | R.LOCAL_ALT,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_AUTO_RTL,
            "Return",
            "auto:rtl",
            _AV_ATT | R.LOCAL_POSITION | R.LOCAL_ALT | R.HOME | R.PREVENT_ARMING,
            _AUTO_FLAGS,
            fixed_wing_requirements=_AV_ATT | R.LOCAL_POSITION_RELAXED | R.LOCAL_ALT | R.HOME | R.PREVENT_ARMING,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_AUTO_TAKEOFF,
            "Takeoff",
            "auto:takeoff",
            _AV_ATT | R.LOCAL_ALT | R.LOCAL_POSITION,
            _AUTO_FLAGS,
            fixed_wing_requirements=_AV_ATT | R.LOCAL_ALT,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_AUTO_LAND,
            "Land",
            "auto:land",
            _AV_ATT | R.LOCAL_ALT | R.LOCAL_POSITION_RELAXED | R.PREVENT_ARMING,
            _AUTO_FLAGS,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_OFFBOARD,
            "Offboard",
            "offboard",
            _AV_ATT,
            frozenset({"flag_control_offboard_enabled", _ATTITUDE, _RATES, _ALLOCATION}),
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_DESCEND,
            "Descend",
            "descend",
            _AV_ATT | R.PREVENT_ARMING,
            frozenset({_AUTO, _ATTITUDE, _RATES, _CLIMB_RATE, _ALLOCATION}),
            user_selectable=False,
        ),
        ModeInfo(
            NS.NAVIGATION_STATE_TERMINATION,
            "Termination",
            "termination",
            R.PREVENT_ARMING,
            frozenset({_TERMINATION}),
            user_selectable=False,
        ),
    )
}

MODE_ALIASES: dict[str, int] = {
    "altitude": NS.NAVIGATION_STATE_ALTCTL,
    "position": NS.NAVIGATION_STATE_POSCTL,
    "mission": NS.NAVIGATION_STATE_AUTO_MISSION,
    "hold": NS.NAVIGATION_STATE_AUTO_LOITER,
    "loiter": NS.NAVIGATION_STATE_AUTO_LOITER,
    "return": NS.NAVIGATION_STATE_AUTO_RTL,
    "rtl": NS.NAVIGATION_STATE_AUTO_RTL,
    "takeoff": NS.NAVIGATION_STATE_AUTO_TAKEOFF,
    "land": NS.NAVIGATION_STATE_AUTO_LAND,
}

VALID_NAV_STATES_MASK = sum(1 << s for s in MODES)
"""The modes a rotary-wing vehicle has (all of them)."""


def valid_nav_states_mask(vehicle_type: int) -> int:
    """``vehicle_status.valid_nav_states_mask``: the modes a vehicle of this type has."""
    return sum(1 << s for s, m in MODES.items() if m.available(vehicle_type))


AUTO_NAV_STATES = frozenset(s for s, m in MODES.items() if _AUTO in m.control_flags)


def mode_name(nav_state: int) -> str:
    mode = MODES.get(nav_state)
    return mode.name if mode else f"nav_state {nav_state}"


def nav_state_from_name(name: str) -> int:
    """The nav_state of a CLI mode name or alias (case-insensitive); ValueError lists the valid names."""
    key = name.strip().lower()
    for state, mode in MODES.items():
        if mode.user_selectable and key in (mode.cli_name, mode.name.lower()):
            return state
    if key in MODE_ALIASES:
        return MODE_ALIASES[key]
    valid = ", ".join(m.cli_name for m in MODES.values() if m.user_selectable)
    raise ValueError(f"unknown mode '{name}' (valid: {valid}; aliases: {', '.join(MODE_ALIASES)})")


def nav_state_from_custom_mode(main_mode: int, sub_mode: int) -> int | None:
    """The nav_state for a PX4 custom main/sub mode, or None if the stack does not support it.

    As in PX4, AUTO with sub mode 0 is Mission, Position's sub modes (1 Orbit, 2 Slow) are modes of their
    own (unsupported here), and the other main modes ignore the sub mode."""
    if main_mode == MainMode.AUTO and sub_mode == 0:
        return NS.NAVIGATION_STATE_AUTO_MISSION
    if main_mode == MainMode.POSCTL and sub_mode != 0:
        return None
    if main_mode != MainMode.AUTO:
        sub_mode = 0
    for state, mode in MODES.items():
        if mode.user_selectable and mode.custom_mode == (main_mode, sub_mode):
            return state
    return None


def nav_state_from_base_mode(base_mode: int) -> int | None:
    """PX4's reading of a plain MAVLink base mode (no custom mode): auto → Mission; manual input with
    guided → Position, with stabilize → Stabilized, else Manual."""
    if base_mode & MAV_MODE_FLAG_AUTO_ENABLED:
        return NS.NAVIGATION_STATE_AUTO_MISSION
    if base_mode & MAV_MODE_FLAG_MANUAL_INPUT_ENABLED:
        if base_mode & MAV_MODE_FLAG_GUIDED_ENABLED:
            return NS.NAVIGATION_STATE_POSCTL
        if base_mode & MAV_MODE_FLAG_STABILIZE_ENABLED:
            return NS.NAVIGATION_STATE_STAB
        return NS.NAVIGATION_STATE_MANUAL
    return None


def control_mode(nav_state: int, armed: bool, vehicle_type: int = ROTARY_WING) -> VehicleControlMode:
    """``vehicle_control_mode`` for a nav_state (PX4 ``getVehicleControlMode``): a fixed-wing vehicle's Manual
    has no attitude or rate loop (the sticks drive the surfaces), and only a rotary-wing vehicle's position
    loops are the multicopter position controller's."""
    mode = MODES.get(nav_state)
    flags = dict.fromkeys(mode.control_flags, True) if mode else {}
    if vehicle_type == FIXED_WING:
        if nav_state == NS.NAVIGATION_STATE_MANUAL:
            flags.pop(_ATTITUDE, None)
            flags.pop(_RATES, None)
    elif not _POSITION_LOOPS.isdisjoint(flags):
        flags[_MC_POSITION_CONTROL] = True
    return VehicleControlMode(flag_armed=armed, source_id=nav_state, **flags)
