"""The failsafe state machine: which action a failure calls for and which mode the vehicle flies in.

Follows PX4's failsafe framework (``src/modules/commander/failsafe/framework.cpp`` and ``failsafe.cpp``)
for the failures this stack detects:

* **command-link loss** (``gcs_connection_lost``): NAV_DLL_ACT (0 disabled, 1 hold, 2 return, 3 land,
  5 terminate, 6 disarm); ignored while disarmed, while landing, and in the modes COM_DLL_EXCEPT exempts
  (bit 0 mission, bit 1 the other auto modes);
* **manual control loss** (``manual_control_lost``): NAV_RCL_ACT, the same actions; ignored while disarmed,
  while landing, in the modes COM_RCL_EXCEPT exempts (bit 0 mission, bit 1 hold and takeoff, bit 2
  offboard), and while the input has been lost since arming (a vehicle armed without sticks flies without
  them), as ``src/modules/commander/failsafe/failsafe.cpp`` does;
* **battery**: LOW only warns; CRITICAL and EMERGENCY act per COM_LOW_BAT_ACT (0 warn, 1 return,
  2 land, 3 return at critical then land at emergency), but only when the warning is worse than it was at
  arming;
* **geofence breach**: GF_ACTION (0 none, 1 warn, 2 hold, 3 return, 4 terminate, 5 land);
* **control chain loss** (a dead or silent estimator or controller, :mod:`stack.commander.control_chain`): of
  attitude control, terminate in the air and disarm on the ground; of position control, land (through the
  mode fallback, descend without a position estimate) — a fixed-wing vehicle descends (Descend: the
  fixed-wing position controller's circling descent), since its landing needs the navigator and the position
  controller — at once and until the user changes mode or disarms; of the airspeed, warn (PX4's airspeed
  selector only advises a return; the fixed-wing controllers fly on without airspeed);
* **mode fallback** (estimator or mission loss): Position falls back to Altitude, Altitude to
  Stabilized, and any mode that cannot run goes to Return — which, when it cannot run either, falls
  through Land and Descend to Terminate. With no local position, an auto mode therefore ends in Descend;
  with position but no home it ends in Land.

The worst active action wins (None < Warn < fallbacks < Hold < Return < Land < Descend < Disarm <
Terminate). An action that allows it is first delayed by COM_FAIL_ACT_T seconds in Hold (PX4's "Failsafe
activated: entering Hold for 5 seconds"). The user takes over by switching mode where the action allows it
(Hold, Return, Land, Descend; never Terminate or Disarm); the action is then reduced to a warning until a
new failure arrives. Link-loss, geofence and Hold/Return/Land actions, once in force, stay until the user
changes mode or disarms; one still waiting out COM_FAIL_ACT_T in Hold goes when its condition clears (a link
regained within the delay returns nothing, and the Hold ends). Battery and fallback actions clear with their
condition. Terminate clears only once the vehicle is disarmed on the ground, where PX4 needs a reboot.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import IntEnum
from functools import cache
from typing import NamedTuple

from stack.commander.geofence import GeofenceAction
from stack.commander.health import can_run, missing_cause
from stack.commander.modes import AUTO_NAV_STATES, FIXED_WING, ROTARY_WING, Requirement
from stack.msg.system import BatteryWarning, VehicleStatus
from stack.params.binding import ParamSet
from stack.params.param import Param

NS = VehicleStatus

class FailsafeParams(ParamSet):
    """The failsafe actions and their exceptions, and the delay before one is taken (the catalogue's)."""

    nav_dll_act: int
    com_dll_except: int
    nav_rcl_act: int
    com_rcl_except: int
    com_low_bat_act: int
    com_fail_act_t: float


PARAMS: tuple[Param, ...] = FailsafeParams.PARAMS

DLL_EXCEPT_MISSION = 1
DLL_EXCEPT_AUTO_MODES = 2
RCL_EXCEPT_MISSION = 1
RCL_EXCEPT_HOLD = 2
RCL_EXCEPT_OFFBOARD = 4


class FailsafeAction(IntEnum):
    """PX4 ``FailsafeBase::Action``, in order of severity."""

    NONE = 0
    WARN = 1
    FALLBACK_POSCTL = 2
    FALLBACK_ALTCTL = 3
    FALLBACK_STAB = 4
    HOLD = 5
    RTL = 6
    LAND = 7
    DESCEND = 8
    DISARM = 9
    TERMINATE = 10


ACTION_NAMES: dict[FailsafeAction, str] = {
    FailsafeAction.NONE: "none",
    FailsafeAction.WARN: "warn",
    FailsafeAction.FALLBACK_POSCTL: "fallback_posctl",
    FailsafeAction.FALLBACK_ALTCTL: "fallback_altctl",
    FailsafeAction.FALLBACK_STAB: "fallback_stabilized",
    FailsafeAction.HOLD: "hold",
    FailsafeAction.RTL: "rtl",
    FailsafeAction.LAND: "land",
    FailsafeAction.DESCEND: "descend",
    FailsafeAction.DISARM: "disarm",
    FailsafeAction.TERMINATE: "terminate",
}

ACTION_MODES: dict[FailsafeAction, int] = {
    FailsafeAction.FALLBACK_POSCTL: NS.NAVIGATION_STATE_POSCTL,
    FailsafeAction.FALLBACK_ALTCTL: NS.NAVIGATION_STATE_ALTCTL,
    FailsafeAction.FALLBACK_STAB: NS.NAVIGATION_STATE_STAB,
    FailsafeAction.HOLD: NS.NAVIGATION_STATE_AUTO_LOITER,
    FailsafeAction.RTL: NS.NAVIGATION_STATE_AUTO_RTL,
    FailsafeAction.LAND: NS.NAVIGATION_STATE_AUTO_LAND,
    FailsafeAction.DESCEND: NS.NAVIGATION_STATE_DESCEND,
    FailsafeAction.TERMINATE: NS.NAVIGATION_STATE_TERMINATION,
}

_TAKEOVER_ACTIONS = frozenset({FailsafeAction.HOLD, FailsafeAction.RTL, FailsafeAction.LAND, FailsafeAction.DESCEND})


class Takeover(IntEnum):
    """How the user may take over from an action (PX4 ``UserTakeoverAllowed``), least restrictive first.
    AUTO becomes ALWAYS (with the COM_FAIL_ACT_T delay) or MODE_SWITCH_ONLY when the action is added."""

    ALWAYS = 0
    MODE_SWITCH_ONLY = 1
    NEVER = 2
    AUTO = 3


class Clear(IntEnum):
    """When an action goes away (PX4 ``ClearCondition``)."""

    WHEN_CONDITION_CLEARS = 0
    ON_MODE_CHANGE_OR_DISARM = 1
    NEVER = 2


class _Options(NamedTuple):
    action: FailsafeAction
    clear: Clear = Clear.WHEN_CONDITION_CLEARS
    takeover: Takeover = Takeover.AUTO


@dataclass(slots=True)
class _Active:
    cause: str
    action: FailsafeAction
    clear: Clear
    takeover: Takeover
    failing: bool = True
    checked: bool = True
    in_force: bool = False
    """Taken effect: selected once with no COM_FAIL_ACT_T delay in the way (or overridden by the user)."""


@dataclass(slots=True)
class FailsafeConditions:
    """The failure states the checks watch (PX4 ``failsafe_flags``)."""

    failing: Requirement = Requirement.NONE
    gcs_connection_lost: bool = False
    manual_control_lost: bool = False
    battery_warning: int = BatteryWarning.NONE
    geofence_breached: bool = False
    attitude_control_lost: bool = False
    position_control_lost: bool = False
    airspeed_lost: bool = False
    landed: bool = True
    host_lost: bool = False
    """A host carrying flight modules of the vehicle is lost (stack.commander.host_loss)."""


class FailsafeResult(NamedTuple):
    action: FailsafeAction
    """The action in force (Hold while a delayed action waits)."""
    delayed_action: FailsafeAction
    cause: str
    nav_state: int
    """The mode to fly: the action's mode, or the user's intended mode."""
    user_intended_nav_state: int
    user_takeover: bool


_TERMINATE = _Options(FailsafeAction.TERMINATE, Clear.NEVER, Takeover.NEVER)
_DISARM = _Options(FailsafeAction.DISARM, takeover=Takeover.NEVER)
_POSITION_CONTROL_LOSS = _Options(FailsafeAction.LAND, Clear.ON_MODE_CHANGE_OR_DISARM, Takeover.MODE_SWITCH_ONLY)
_FW_POSITION_CONTROL_LOSS = _Options(FailsafeAction.DESCEND, Clear.ON_MODE_CHANGE_OR_DISARM, Takeover.MODE_SWITCH_ONLY)
_AIRSPEED_LOSS = _Options(FailsafeAction.WARN)
_HOST_LOSS = _Options(FailsafeAction.LAND, Clear.ON_MODE_CHANGE_OR_DISARM, Takeover.MODE_SWITCH_ONLY)


@cache
def _from_link_loss_param(value: int) -> _Options:
    if value == 1:
        return _Options(FailsafeAction.HOLD, Clear.ON_MODE_CHANGE_OR_DISARM)
    if value == 2:
        return _Options(FailsafeAction.RTL, Clear.ON_MODE_CHANGE_OR_DISARM)
    if value == 3:
        return _Options(FailsafeAction.LAND, Clear.ON_MODE_CHANGE_OR_DISARM)
    if value == 5:
        return _TERMINATE
    if value == 6:
        return _DISARM
    return _Options(FailsafeAction.NONE)


@cache
def _from_geofence_param(value: int) -> _Options:
    action = GeofenceAction(value)
    if action == GeofenceAction.NONE:
        return _Options(FailsafeAction.NONE)
    if action == GeofenceAction.HOLD:
        return _Options(FailsafeAction.HOLD, Clear.ON_MODE_CHANGE_OR_DISARM, Takeover.MODE_SWITCH_ONLY)
    if action == GeofenceAction.RETURN:
        return _Options(FailsafeAction.RTL, Clear.ON_MODE_CHANGE_OR_DISARM)
    if action == GeofenceAction.TERMINATE:
        return _Options(FailsafeAction.TERMINATE, Clear.NEVER, Takeover.NEVER)
    if action == GeofenceAction.LAND:
        return _Options(FailsafeAction.LAND, Clear.ON_MODE_CHANGE_OR_DISARM)
    return _Options(FailsafeAction.WARN)


@cache
def _from_battery_param(value: int, warning: int) -> _Options:
    if warning == BatteryWarning.CRITICAL:
        action = {1: FailsafeAction.RTL, 2: FailsafeAction.LAND, 3: FailsafeAction.RTL}.get(value, FailsafeAction.WARN)
    elif warning >= BatteryWarning.EMERGENCY:
        action = {1: FailsafeAction.RTL, 2: FailsafeAction.LAND, 3: FailsafeAction.LAND}.get(value, FailsafeAction.WARN)
    else:
        action = FailsafeAction.WARN
    return _Options(action)


BATTERY_CAUSES = {
    BatteryWarning.LOW: "battery_low",
    BatteryWarning.CRITICAL: "battery_critical",
    BatteryWarning.EMERGENCY: "battery_emergency",
    BatteryWarning.FAILED: "battery_emergency",
}


def mode_fallback(
    failing: Requirement, intended: int, vehicle_type: int = ROTARY_WING
) -> tuple[FailsafeAction, int]:
    """PX4 ``checkModeFallback``: the fallback action for the intended mode and the mode it leads to."""
    action = FailsafeAction.NONE
    if intended == NS.NAVIGATION_STATE_POSCTL and not can_run(intended, failing, vehicle_type):
        action, intended = FailsafeAction.FALLBACK_ALTCTL, NS.NAVIGATION_STATE_ALTCTL
    if intended == NS.NAVIGATION_STATE_ALTCTL and not can_run(intended, failing, vehicle_type):
        action, intended = FailsafeAction.FALLBACK_STAB, NS.NAVIGATION_STATE_STAB
    if not can_run(intended, failing, vehicle_type):
        action, intended = FailsafeAction.RTL, NS.NAVIGATION_STATE_AUTO_RTL
    return action, intended


_FALLBACK_CHAIN = (
    FailsafeAction.FALLBACK_POSCTL,
    FailsafeAction.FALLBACK_ALTCTL,
    FailsafeAction.FALLBACK_STAB,
    FailsafeAction.HOLD,
    FailsafeAction.RTL,
    FailsafeAction.LAND,
    FailsafeAction.DESCEND,
)


def runnable_action(
    action: FailsafeAction, failing: Requirement, vehicle_type: int = ROTARY_WING
) -> FailsafeAction:
    """The action itself if its mode can run, else the next one down PX4's fallback chain."""
    chain = _FALLBACK_CHAIN
    if action not in chain:
        return action
    for candidate in chain[chain.index(action) :]:
        if can_run(ACTION_MODES[candidate], failing, vehicle_type):
            return candidate
    return FailsafeAction.TERMINATE


class Failsafe:
    """Call ``update`` every commander cycle with the arming state, the user's intended mode (and whether
    the user just changed it) and the current failure conditions. ``vehicle_type`` (rotary wing unless set)
    decides which modes can run and the action on a loss of position control."""

    __slots__ = (
        "_actions",
        "_battery_warning_at_arming",
        "_delay_us",
        "_last_update_us",
        "_manual_control_lost_at_arming",
        "_p",
        "_selected",
        "_takeover_active",
        "_was_armed",
        "vehicle_type",
    )

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._actions: dict[str, _Active] = {}
        self._selected = FailsafeAction.NONE
        self._delay_us = 0
        self._takeover_active = False
        self._was_armed = False
        self._battery_warning_at_arming = BatteryWarning.NONE
        self._manual_control_lost_at_arming = False
        self._last_update_us = 0
        self.vehicle_type = ROTARY_WING
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = FailsafeParams.from_params(params)

    @property
    def selected_action(self) -> FailsafeAction:
        return self._selected

    def update(
        self,
        now_us: int,
        armed: bool,
        intended: int,
        intended_updated: bool,
        cond: FailsafeConditions,
        gf_action: int,
    ) -> FailsafeResult:
        p = self._p
        dt_us = max(now_us - self._last_update_us, 0) if self._last_update_us else 0
        self._last_update_us = now_us
        self._delay_us = max(self._delay_us - dt_us, 0)

        if self._was_armed and not armed:
            self._remove_actions(Clear.ON_MODE_CHANGE_OR_DISARM)
        elif armed and not self._was_armed:
            self._battery_warning_at_arming = cond.battery_warning
            self._manual_control_lost_at_arming = cond.manual_control_lost
        if not cond.manual_control_lost:
            self._manual_control_lost_at_arming = False
        self._was_armed = armed
        if intended_updated or self._takeover_active:
            self._remove_actions(Clear.ON_MODE_CHANGE_OR_DISARM)

        failing = cond.failing
        vehicle_type = self.vehicle_type
        landing = intended == NS.NAVIGATION_STATE_AUTO_LAND
        dll_action = p.nav_dll_act
        if dll_action != 0 and armed and not landing and not self._dll_exempt(intended):
            self._check("gcs_connection_loss", cond.gcs_connection_lost, _from_link_loss_param(dll_action))
        rcl_action = p.nav_rcl_act
        rcl_ignored = self._manual_control_lost_at_arming or self._rcl_exempt(intended)
        if rcl_action != 0 and armed and not landing and not rcl_ignored:
            self._check("manual_control_loss", cond.manual_control_lost, _from_link_loss_param(rcl_action))

        self._check("geofence_breach", cond.geofence_breached, _from_geofence_param(gf_action))
        if armed:
            lost_attitude = _DISARM if cond.landed else _TERMINATE
            self._check("attitude_control_loss", cond.attitude_control_lost, lost_attitude)
            lost_position = _FW_POSITION_CONTROL_LOSS if vehicle_type == FIXED_WING else _POSITION_CONTROL_LOSS
            self._check("position_control_loss", cond.position_control_lost, lost_position)
            self._check("airspeed_loss", cond.airspeed_lost, _AIRSPEED_LOSS)
            self._check("host_loss", cond.host_lost, _HOST_LOSS)

        warning = cond.battery_warning
        if warning > BatteryWarning.NONE:
            bat_action = p.com_low_bat_act if warning > self._battery_warning_at_arming else 0
            self._check(BATTERY_CAUSES[BatteryWarning(min(warning, 4))], True, _from_battery_param(bat_action, warning))

        fallback, _ = mode_fallback(failing, intended, vehicle_type)
        if fallback != FailsafeAction.NONE:
            cause = missing_cause(intended, failing, vehicle_type)
            self._check(cause, True, _Options(fallback, takeover=Takeover.ALWAYS))

        for key in [k for k, a in self._actions.items() if not a.checked]:
            self._condition_cleared(key)
        for active in self._actions.values():
            active.checked = False

        if self._selected > FailsafeAction.HOLD or not can_run(NS.NAVIGATION_STATE_AUTO_LOITER, failing, vehicle_type):
            self._delay_us = 0
        if self._takeover_active:
            self._delay_us = 0

        return self._select(armed, intended, intended_updated, failing)

    def latch_termination(self) -> None:
        """Terminated already (a restarted commander taking over a terminated vehicle): it stays so."""
        self._selected = FailsafeAction.TERMINATE

    def clear_termination(self) -> None:
        """The terminated vehicle was disarmed on the ground: it may fly again (PX4 asks for a reboot)."""
        self._selected = FailsafeAction.NONE
        self._actions.clear()

    def _dll_exempt(self, intended: int) -> bool:
        mask = self._p.com_dll_except
        if intended == NS.NAVIGATION_STATE_AUTO_MISSION:
            return bool(mask & DLL_EXCEPT_MISSION)
        if intended in AUTO_NAV_STATES:
            return bool(mask & DLL_EXCEPT_AUTO_MODES)
        return False

    def _rcl_exempt(self, intended: int) -> bool:
        mask = self._p.com_rcl_except
        if intended == NS.NAVIGATION_STATE_AUTO_MISSION:
            return bool(mask & RCL_EXCEPT_MISSION)
        if intended in (NS.NAVIGATION_STATE_AUTO_LOITER, NS.NAVIGATION_STATE_AUTO_TAKEOFF):
            return bool(mask & RCL_EXCEPT_HOLD)
        if intended == NS.NAVIGATION_STATE_OFFBOARD:
            return bool(mask & RCL_EXCEPT_OFFBOARD)
        return False

    def _check(self, cause: str, failing: bool, options: _Options) -> None:
        active = self._actions.get(cause)
        if not failing:
            if active is not None:
                active.checked = True
                self._condition_cleared(cause)
            return
        if options.action == FailsafeAction.NONE:
            return
        if active is not None:
            active.failing = True
            active.checked = True
            active.action = options.action
            return
        takeover = options.takeover
        if takeover == Takeover.AUTO:
            if self._p.com_fail_act_t > 0.1:
                if options.action != FailsafeAction.WARN and self._delay_us == 0:
                    self._delay_us = round(self._p.com_fail_act_t * 1e6)
                takeover = Takeover.ALWAYS
            else:
                takeover = Takeover.MODE_SWITCH_ONLY
        self._actions[cause] = _Active(cause, options.action, options.clear, takeover)
        if options.action >= FailsafeAction.HOLD:
            self._takeover_active = False

    def _condition_cleared(self, cause: str) -> None:
        active = self._actions[cause]
        # An action still waiting out COM_FAIL_ACT_T in Hold goes with its condition (a link regained in time
        # returns nothing); one in force stays as its clear condition says.
        if active.clear == Clear.WHEN_CONDITION_CLEARS or (active.clear != Clear.NEVER and not active.in_force):
            del self._actions[cause]
        else:
            active.failing = False

    def _remove_actions(self, clear: Clear) -> None:
        for cause in [c for c, a in self._actions.items() if a.clear == clear and not a.failing]:
            del self._actions[cause]

    def _select(self, armed: bool, intended: int, intended_updated: bool, failing: Requirement) -> FailsafeResult:
        if self._selected == FailsafeAction.TERMINATE:
            return self._result(FailsafeAction.TERMINATE, FailsafeAction.NONE, "terminated", intended, False)
        if not armed:
            return self._result(FailsafeAction.NONE, FailsafeAction.NONE, "", intended, False)

        selected = FailsafeAction.NONE
        cause = ""
        takeover = Takeover.ALWAYS
        for active in self._actions.values():
            takeover = max(takeover, active.takeover)
            if active.action > selected:
                selected, cause = active.action, active.cause

        delayed = FailsafeAction.NONE
        if (
            self._delay_us > 0
            and not self._takeover_active
            and takeover <= Takeover.MODE_SWITCH_ONLY
            and selected > FailsafeAction.WARN
            and selected not in (FailsafeAction.DISARM, FailsafeAction.TERMINATE)
        ):
            delayed, selected, takeover = selected, FailsafeAction.HOLD, Takeover.MODE_SWITCH_ONLY
        else:
            for active in self._actions.values():
                active.in_force = True

        wants_takeover = intended_updated and self._selected == selected
        user_takeover = False
        if selected in _TAKEOVER_ACTIONS and takeover != Takeover.NEVER and (self._takeover_active or wants_takeover):
            selected, delayed, user_takeover = FailsafeAction.WARN, FailsafeAction.NONE, True
            fallback, _ = mode_fallback(failing, intended, self.vehicle_type)
            if fallback > selected:
                selected = fallback

        selected = runnable_action(selected, failing, self.vehicle_type)

        # Already landing: a Return would only climb away from the landing spot.
        if (
            intended == NS.NAVIGATION_STATE_AUTO_LAND
            and FailsafeAction.RTL in (selected, delayed)
            and can_run(NS.NAVIGATION_STATE_AUTO_LAND, failing, self.vehicle_type)
        ):
            selected, delayed = FailsafeAction.WARN, FailsafeAction.NONE
        return self._result(selected, delayed, cause, intended, user_takeover)

    def _result(
        self, action: FailsafeAction, delayed: FailsafeAction, cause: str, intended: int, user_takeover: bool
    ) -> FailsafeResult:
        self._selected = action
        self._takeover_active = user_takeover
        nav_state = ACTION_MODES.get(action, intended)
        return FailsafeResult(
            action, delayed, cause if action > FailsafeAction.NONE else "", nav_state, intended, user_takeover
        )
