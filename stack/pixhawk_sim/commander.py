"""The simulated Pixhawk's commander: arming, mode changes, the Offboard signal, its loss failsafe, auto-disarm.

A small PX4 commander (``src/modules/commander/Commander.cpp``, ``failsafe/failsafe.cpp``), clocked by its
caller and free of I/O:

* Arming (MAV_CMD_COMPONENT_ARM_DISARM): refused, unless forced with param2 = 21196, when the vehicle is not
  landed, when the attitude is beyond the failure detector's FD_FAIL_R / FD_FAIL_P, or when the mode cannot be
  armed in: Offboard without a setpoint stream, a stick mode (no RC), Land or Return, a mode that is not
  simulated. Arming an armed vehicle is accepted and changes nothing, as PX4 does. Disarming in the air needs
  the force code. A refusal is TEMPORARILY_REJECTED with the reason, which is what PX4 answers.
* Mode changes (MAV_CMD_DO_SET_MODE): PX4 takes any mode while disarmed; armed, only a mode that can run now
  (Offboard needs the setpoint stream: it must exist before the switch). Modes that need PX4's navigator
  (takeoff, mission, return...) are not simulated and are DENIED.
* The Offboard signal is alive while a setpoint arrived within COM_OF_LOSS_T (the stack's commander's rule,
  :func:`stack.commander.offboard.signal_alive`). When it is lost in Offboard the
  failsafe flies COM_OBL_RC_ACT: Position, Altitude and Stabilized fall through to Hold, as PX4's
  ``FailsafeBase::getSelectedAction`` does when the stick modes cannot run; Land; Hold; Terminate (motors off
  until restart); Disarm. Like PX4's mode fallback it clears when the signal returns: the vehicle flies
  Offboard again. Armed in a mode it cannot fly (only by forced arming) it holds.
* Auto-disarm: COM_DISARM_LAND after landing once it has taken off, COM_DISARM_PRFLT after arming without
  taking off (``Commander::checkForAutoDisarm``, the stack's commander's :mod:`stack.commander.auto_disarm`).

Not modelled: RC, geofence, battery and data-link failsafes, COM_FAIL_ACT_T's delay, the pre-arm checks of
sensors and estimators (the simulated sensors and the estimate, which is the simulator's truth, are healthy).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from pymavlink.dialects.v20 import common as mavlink

from stack.commander import offboard
from stack.commander.auto_disarm import AutoDisarm, AutoDisarmParams
from stack.commander.offboard import OffboardLossAction
from stack.mavlink.px4_modes import Px4Mode, name
from stack.pixhawk_sim.modes import ARMING_PREVENTED_MODES, FLOWN_MODES, MANUAL_CONTROL_MODES, SELECTABLE_MODES

INITIAL_MODE = Px4Mode.POSCTL
"""PX4's initial user intention (``UserModeIntention``); without RC it cannot run, so arming needs a mode change."""

_OFFBOARD_LOSS_MODES = {
    OffboardLossAction.POSITION: Px4Mode.AUTO_LOITER,
    OffboardLossAction.ALTITUDE: Px4Mode.AUTO_LOITER,
    OffboardLossAction.STABILIZED: Px4Mode.AUTO_LOITER,
    OffboardLossAction.HOLD: Px4Mode.AUTO_LOITER,
    OffboardLossAction.LAND: Px4Mode.AUTO_LAND,
    OffboardLossAction.TERMINATE: Px4Mode.TERMINATION,
}
"""COM_OBL_RC_ACT → the mode flown (Disarm has none)."""


class Verdict(NamedTuple):
    """A command's outcome: MAV_RESULT and, for a refusal, the reason (sent as STATUSTEXT too)."""

    result: int
    reason: str = ""


ACCEPTED = Verdict(mavlink.MAV_RESULT_ACCEPTED)


class Notice(NamedTuple):
    """A STATUSTEXT to send: MAV_SEVERITY and text."""

    severity: int
    text: str


class Condition(NamedTuple):
    """What the commander needs to know about the vehicle now."""

    landed: bool
    maybe_landed: bool
    roll: float
    """rad"""
    pitch: float
    """rad"""


class Px4Commander:
    """See the module docstring. ``update`` every cycle; commands and setpoints as they arrive."""

    def __init__(self, params: Mapping[str, object]) -> None:
        self.armed = False
        self.user_mode = INITIAL_MODE
        """The mode the user selected (PX4's ``nav_state_user_intention``)."""
        self.mode = INITIAL_MODE
        """The mode flown (PX4's ``nav_state``): the user's, or the failsafe's."""
        self.failsafe = False
        self.terminated = False
        self.have_taken_off = False
        self._last_setpoint_us: int | None = None
        self._armed_us = 0
        self._auto_disarm = AutoDisarm()
        self._notices: list[Notice] = []
        self.set_params(params)

    def set_params(self, params: Mapping[str, object]) -> None:
        self._offboard_loss_s = float(params["COM_OF_LOSS_T"])
        self._loss_action = OffboardLossAction(int(params["COM_OBL_RC_ACT"]))
        self._auto_disarm.set_params(AutoDisarmParams.from_params(params))
        self._fail_roll = math.radians(float(params["FD_FAIL_R"]))
        self._fail_pitch = math.radians(float(params["FD_FAIL_P"]))

    def take_notices(self) -> list[Notice]:
        notices, self._notices = self._notices, []
        return notices

    def _notify(self, severity: int, text: str) -> None:
        self._notices.append(Notice(severity, text))

    # ------------------------------------------------------------------ Offboard signal

    def offboard_setpoint(self, now_us: int) -> None:
        """A setpoint arrived: proof of life of the Offboard signal."""
        self._last_setpoint_us = now_us

    def offboard_signal(self, now_us: int) -> bool:
        return offboard.signal_alive(self._last_setpoint_us, now_us, self._offboard_loss_s)

    # ------------------------------------------------------------------ commands

    def arm_disarm(self, arm: bool, force: bool, now_us: int, condition: Condition) -> Verdict:
        if arm:
            return self._arm(force, now_us, condition)
        if not self.armed:
            return ACCEPTED
        if not force and not (condition.landed or condition.maybe_landed):
            return self._refuse("Disarming denied: not landed")
        self._disarm("by command" if not force else "forced by command")
        return ACCEPTED

    def _arm(self, force: bool, now_us: int, condition: Condition) -> Verdict:
        if self.terminated:
            return self._refuse("Arming denied: flight terminated, restart the autopilot")
        if self.armed:
            return ACCEPTED
        if not force:
            reason = self.arming_denial(now_us, condition)
            if reason:
                return self._refuse(f"Arming denied: {reason}")
        self.armed = True
        self._armed_us = now_us
        self.have_taken_off = False
        self._auto_disarm.reset()
        self._notify(mavlink.MAV_SEVERITY_INFO, "Armed by external command" + (" (forced)" if force else ""))
        self._update_mode(now_us)
        return ACCEPTED

    def arming_denial(self, now_us: int, condition: Condition) -> str:
        """Why arming (unforced) would be refused now, or "" (the pre-arm check of SYS_STATUS)."""
        if not (condition.landed or condition.maybe_landed):
            return "vehicle not landed"
        if abs(condition.roll) > self._fail_roll:
            return "attitude failure (roll)"
        if abs(condition.pitch) > self._fail_pitch:
            return "attitude failure (pitch)"
        mode = self.user_mode
        if mode is Px4Mode.OFFBOARD and not self.offboard_signal(now_us):
            return "no offboard signal"
        if mode in MANUAL_CONTROL_MODES:
            return f"no manual control input for {name(mode)}"
        if mode in ARMING_PREVENTED_MODES:
            return f"not possible in {name(mode)}"
        if mode not in FLOWN_MODES:
            return f"{name(mode)} is not simulated"
        return ""

    def set_mode(self, mode: Px4Mode | None, now_us: int) -> Verdict:
        """MAV_CMD_DO_SET_MODE to a PX4 custom mode (None: a custom mode PX4 does not define)."""
        if mode is None:
            return self._refuse("Mode change denied: unknown mode", mavlink.MAV_RESULT_DENIED)
        if mode not in SELECTABLE_MODES:
            return self._refuse(f"Mode change denied: {name(mode)} is not simulated", mavlink.MAV_RESULT_DENIED)
        if self.armed:
            if mode in MANUAL_CONTROL_MODES:
                return self._refuse(f"Switching to {name(mode)} is currently not possible: no manual control input")
            if mode is Px4Mode.OFFBOARD and not self.offboard_signal(now_us):
                return self._refuse("Switching to OFFBOARD is currently not possible: no offboard signal")
        if mode is not self.user_mode:
            self.user_mode = mode
            self._notify(mavlink.MAV_SEVERITY_INFO, f"Mode: {name(mode)}")
        self._update_mode(now_us)
        return ACCEPTED

    def _refuse(self, reason: str, result: int = mavlink.MAV_RESULT_TEMPORARILY_REJECTED) -> Verdict:
        self._notify(mavlink.MAV_SEVERITY_CRITICAL, reason)
        return Verdict(result, reason)

    # ------------------------------------------------------------------ cycle

    def update(self, now_us: int, condition: Condition) -> None:
        """Failsafe and auto-disarm with the vehicle's state now."""
        if self.armed:
            if not condition.landed:
                self.have_taken_off = True
            self._check_auto_disarm(now_us, condition)
        self._update_mode(now_us)

    def _check_auto_disarm(self, now_us: int, condition: Condition) -> None:
        if self._auto_disarm.update(now_us, condition.landed, self.have_taken_off):
            self._disarm("landed" if self.have_taken_off else "no takeoff after arming")

    def _disarm(self, why: str) -> None:
        self.armed = False
        self._auto_disarm.reset()
        self._notify(mavlink.MAV_SEVERITY_INFO, f"Disarmed ({why})")

    def _update_mode(self, now_us: int) -> None:
        """The mode flown: the user's, or the failsafe's while its condition holds."""
        if self.terminated:
            return
        mode, cause = self.user_mode, ""
        if self.armed:
            if self.user_mode is Px4Mode.OFFBOARD and not self.offboard_signal(now_us):
                if self._loss_action is OffboardLossAction.DISARM:
                    self._notify(mavlink.MAV_SEVERITY_CRITICAL, "Failsafe: offboard signal lost, disarming")
                    self._disarm("failsafe")
                    mode = self.user_mode
                else:
                    mode, cause = _OFFBOARD_LOSS_MODES[self._loss_action], "offboard signal lost"
            elif self.user_mode not in FLOWN_MODES:
                mode, cause = Px4Mode.AUTO_LOITER, f"{name(self.user_mode)} cannot run"
        failsafe = bool(cause)
        if failsafe and not self.failsafe:
            self._notify(mavlink.MAV_SEVERITY_CRITICAL, f"Failsafe activated: {cause}, {name(mode)}")
        elif self.failsafe and not failsafe and self.armed:
            self._notify(mavlink.MAV_SEVERITY_INFO, f"Failsafe cleared: {name(mode)}")
        self.failsafe = failsafe
        if mode is Px4Mode.TERMINATION:
            self.terminated = True
        self.mode = mode
