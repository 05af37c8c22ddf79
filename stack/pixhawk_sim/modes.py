"""What each PX4 flight mode means to the simulated Pixhawk: can it fly it, what does it need, which flags.

The modes themselves (names, ``custom_mode`` encoding) are ``stack.mavlink.px4_modes``. The simulated
Pixhawk has no RC receiver (as PX4 with COM_RC_IN_MODE 4), so the modes flown from sticks cannot run; it
flies Offboard, Hold (AUTO.LOITER) and Land (AUTO.LAND) and has no navigator for the other auto modes.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink

from stack.mavlink.px4_modes import Px4Mode

FLOWN_MODES = frozenset({Px4Mode.OFFBOARD, Px4Mode.AUTO_LOITER, Px4Mode.AUTO_LAND})
"""The modes the simulated Pixhawk flies."""

MANUAL_CONTROL_MODES = frozenset(
    {
        Px4Mode.MANUAL,
        Px4Mode.ALTCTL,
        Px4Mode.POSCTL,
        Px4Mode.POSCTL_ORBIT,
        Px4Mode.POSCTL_SLOW,
        Px4Mode.ACRO,
        Px4Mode.STABILIZED,
        Px4Mode.RATTITUDE,
        Px4Mode.ALTITUDE_CRUISE,
    }
)
"""Modes PX4 flies from manual control input (``mode_req_manual_control``); without RC they cannot run."""

ARMING_PREVENTED_MODES = frozenset({Px4Mode.AUTO_LAND, Px4Mode.AUTO_RTL})
"""Modes PX4 will not arm in (``mode_req_prevent_arming``)."""

SELECTABLE_MODES = FLOWN_MODES | MANUAL_CONTROL_MODES
"""Modes a DO_SET_MODE may select while disarmed (PX4 allows any mode then; arming checks it later). The other
auto modes need PX4's navigator (takeoff, mission, return...), which is not simulated."""

AUTO_MODES = frozenset(m for m in Px4Mode if m.name.startswith("AUTO_"))

_ACRO_LIKE = frozenset({Px4Mode.ACRO})
"""Manual modes that control rates only (no attitude stabilisation)."""


def base_mode_flags(mode: Px4Mode, armed: bool, offboard_attitude: bool) -> int:
    """HEARTBEAT ``base_mode`` as PX4's ``streams/HEARTBEAT.hpp`` sets it from ``vehicle_control_mode``: custom
    mode always; armed; manual input in stick modes; stabilize when attitude is controlled; auto, stabilize
    and guided in auto modes. In Offboard the attitude is controlled unless the setpoints are body rates."""
    flags = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        flags |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    if mode in MANUAL_CONTROL_MODES:
        flags |= mavlink.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
        if mode not in _ACRO_LIKE:
            flags |= mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
    elif mode in AUTO_MODES:
        flags |= (
            mavlink.MAV_MODE_FLAG_AUTO_ENABLED
            | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
            | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
        )
    elif mode is Px4Mode.OFFBOARD and offboard_attitude:
        flags |= mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
    return flags
