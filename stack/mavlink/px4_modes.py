"""PX4's custom flight modes on MAVLink, defined once for the adapter, the simulated Pixhawk and ``inspect``.

PX4 puts its flight mode in HEARTBEAT ``custom_mode`` (and takes it in MAV_CMD_DO_SET_MODE param2/param3)
as the union ``px4_custom_mode`` of ``src/modules/commander/px4_custom_mode.h``: bits 0–15 reserved,
the main mode (``PX4_CUSTOM_MAIN_MODE_*``) in bits 16–23 and the sub mode (``PX4_CUSTOM_SUB_MODE_*``)
in bits 24–31. The same header's ``get_px4_custom_mode(nav_state)`` maps ``vehicle_status.nav_state``
to it; :data:`NAV_STATE_MODE` is that table for the nav states the stack has.
"""

from __future__ import annotations

from enum import Enum, IntEnum

from stack.msg.system import VehicleStatus as NS


class MainMode(IntEnum):
    """``PX4_CUSTOM_MAIN_MODE_*``."""

    MANUAL = 1
    ALTCTL = 2
    POSCTL = 3
    AUTO = 4
    ACRO = 5
    OFFBOARD = 6
    STABILIZED = 7
    RATTITUDE_LEGACY = 8
    SIMPLE = 9
    TERMINATION = 10
    ALTITUDE_CRUISE = 11


class AutoSubMode(IntEnum):
    """``PX4_CUSTOM_SUB_MODE_AUTO_*`` (7 was RTGS, deleted from PX4 in 2020)."""

    READY = 1
    TAKEOFF = 2
    LOITER = 3
    MISSION = 4
    RTL = 5
    LAND = 6
    FOLLOW_TARGET = 8
    PRECLAND = 9
    VTOL_TAKEOFF = 10
    EXTERNAL1 = 11


class PosctlSubMode(IntEnum):
    """``PX4_CUSTOM_SUB_MODE_POSCTL_*``."""

    POSCTL = 0
    ORBIT = 1
    SLOW = 2


class Px4Mode(Enum):
    """A PX4 flight mode as its (main mode, sub mode) pair."""

    MANUAL = (MainMode.MANUAL, 0)
    ALTCTL = (MainMode.ALTCTL, 0)
    POSCTL = (MainMode.POSCTL, PosctlSubMode.POSCTL)
    POSCTL_ORBIT = (MainMode.POSCTL, PosctlSubMode.ORBIT)
    POSCTL_SLOW = (MainMode.POSCTL, PosctlSubMode.SLOW)
    AUTO_READY = (MainMode.AUTO, AutoSubMode.READY)
    AUTO_TAKEOFF = (MainMode.AUTO, AutoSubMode.TAKEOFF)
    AUTO_LOITER = (MainMode.AUTO, AutoSubMode.LOITER)
    AUTO_MISSION = (MainMode.AUTO, AutoSubMode.MISSION)
    AUTO_RTL = (MainMode.AUTO, AutoSubMode.RTL)
    AUTO_LAND = (MainMode.AUTO, AutoSubMode.LAND)
    AUTO_FOLLOW_TARGET = (MainMode.AUTO, AutoSubMode.FOLLOW_TARGET)
    AUTO_PRECLAND = (MainMode.AUTO, AutoSubMode.PRECLAND)
    AUTO_VTOL_TAKEOFF = (MainMode.AUTO, AutoSubMode.VTOL_TAKEOFF)
    EXTERNAL1 = (MainMode.AUTO, AutoSubMode.EXTERNAL1)
    ACRO = (MainMode.ACRO, 0)
    OFFBOARD = (MainMode.OFFBOARD, 0)
    STABILIZED = (MainMode.STABILIZED, 0)
    RATTITUDE = (MainMode.RATTITUDE_LEGACY, 0)
    TERMINATION = (MainMode.TERMINATION, 0)
    ALTITUDE_CRUISE = (MainMode.ALTITUDE_CRUISE, 0)

    @property
    def main_mode(self) -> int:
        return int(self.value[0])

    @property
    def sub_mode(self) -> int:
        return int(self.value[1])


_BY_PAIR: dict[tuple[int, int], Px4Mode] = {(m.main_mode, m.sub_mode): m for m in Px4Mode}

_SUB_MODE_MAIN_MODES = frozenset({MainMode.AUTO, MainMode.POSCTL})
"""The main modes whose sub mode selects a mode; the others carry sub mode 0."""


def encode(mode: Px4Mode) -> int:
    """HEARTBEAT ``custom_mode``: main mode in bits 16–23, sub mode in bits 24–31."""
    return (mode.main_mode << 16) | (mode.sub_mode << 24)


def main_sub(custom_mode: int) -> tuple[int, int]:
    """The (main mode, sub mode) numbers of a HEARTBEAT or SET_MODE ``custom_mode``, whatever they are."""
    return (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF


def decode(custom_mode: int) -> Px4Mode | None:
    """The mode a HEARTBEAT ``custom_mode`` carries, or None for a value PX4 does not define.

    The reserved low 16 bits are ignored, and so is the sub mode of a main mode that has none."""
    main, sub = main_sub(custom_mode)
    if main not in _SUB_MODE_MAIN_MODES:
        sub = 0
    return _BY_PAIR.get((main, sub))


def name(mode: Px4Mode) -> str:
    """PX4's spelling as QGroundControl and MAVSDK logs show it: "OFFBOARD", "AUTO.LOITER", "POSCTL.ORBIT"."""
    return mode.name.replace("_", ".", 1) if mode.main_mode in _SUB_MODE_MAIN_MODES else mode.name


def describe(custom_mode: int) -> str:
    """A HEARTBEAT ``custom_mode`` as text: the mode's name, or the raw main/sub numbers."""
    mode = decode(custom_mode)
    if mode is not None:
        return name(mode)
    main, sub = main_sub(custom_mode)
    return f"main {main} sub {sub}"


NAV_STATE_MODE: dict[int, Px4Mode] = {
    NS.NAVIGATION_STATE_MANUAL: Px4Mode.MANUAL,
    NS.NAVIGATION_STATE_ALTCTL: Px4Mode.ALTCTL,
    NS.NAVIGATION_STATE_POSCTL: Px4Mode.POSCTL,
    NS.NAVIGATION_STATE_AUTO_MISSION: Px4Mode.AUTO_MISSION,
    NS.NAVIGATION_STATE_AUTO_LOITER: Px4Mode.AUTO_LOITER,
    NS.NAVIGATION_STATE_AUTO_RTL: Px4Mode.AUTO_RTL,
    NS.NAVIGATION_STATE_ACRO: Px4Mode.ACRO,
    NS.NAVIGATION_STATE_DESCEND: Px4Mode.AUTO_LAND,
    NS.NAVIGATION_STATE_TERMINATION: Px4Mode.TERMINATION,
    NS.NAVIGATION_STATE_OFFBOARD: Px4Mode.OFFBOARD,
    NS.NAVIGATION_STATE_STAB: Px4Mode.STABILIZED,
    NS.NAVIGATION_STATE_AUTO_TAKEOFF: Px4Mode.AUTO_TAKEOFF,
    NS.NAVIGATION_STATE_AUTO_LAND: Px4Mode.AUTO_LAND,
    NS.NAVIGATION_STATE_RATTITUDE: Px4Mode.RATTITUDE,
    NS.NAVIGATION_STATE_EXTERNAL1: Px4Mode.EXTERNAL1,
}
"""``get_px4_custom_mode(nav_state)`` for the stack's nav states (Rattitude: PX4's legacy main mode 8).
Descend and Land share AUTO.LAND, as in PX4."""

_MODE_NAV_STATE: dict[Px4Mode, int] = {}
for _nav_state, _mode in NAV_STATE_MODE.items():
    _MODE_NAV_STATE.setdefault(_mode, _nav_state)
_MODE_NAV_STATE[Px4Mode.AUTO_LAND] = NS.NAVIGATION_STATE_AUTO_LAND


def from_nav_state(nav_state: int) -> Px4Mode | None:
    """The PX4 mode of a ``vehicle_status.nav_state``, or None for one PX4 has no custom mode for."""
    return NAV_STATE_MODE.get(nav_state)


def to_nav_state(mode: Px4Mode) -> int | None:
    """The stack's ``nav_state`` for a PX4 mode (AUTO.LAND → Land), or None where the stack has no such mode."""
    return _MODE_NAV_STATE.get(mode)
