"""The commander: arming, flight modes, commands and failsafes (PX4 ``src/modules/commander/Commander.cpp``).

:class:`Commander` is clocked by its caller: ``update(now_us, inputs)`` every cycle (PX4: 100 Hz) with the
latest :class:`~stack.commander.health.CommanderInputs`, and ``handle_command(cmd, now_us)`` for each
``vehicle_command``, which returns its ``vehicle_command_ack`` (none for another vehicle's command):

* ACCEPTED; DENIED with a reason when a parameter is NaN, infinite or out of range (``result_param2`` names
  the offending parameter, 1–7, as MAVLink's COMMAND_ACK does) or the mode is unknown; TEMPORARILY_REJECTED
  with a reason when the command is valid but the vehicle cannot do it now (pre-arm checks, mode
  requirements, not landed...), which is what PX4 answers for refused arming and mode changes; UNSUPPORTED
  for any other command. A refused command changes nothing. A command addressed to another system or
  component (``target_system`` not MAV_SYS_ID or 0, ``target_component`` not MAV_COMP_ID or 0) is ignored
  without an answer, as PX4's ``Commander::handle_command`` does (:mod:`stack.commander.command_checks`).

Commands (MAVLink ids; PX4 encodings):

* COMPONENT_ARM_DISARM (400): param1 1 arm / 0 disarm (rounded, as PX4 does), param2 21196 forces (arming
  skips the checks, disarming skips the landed check).
* DO_SET_MODE (176): param1 base mode; with MAV_MODE_FLAG_CUSTOM_MODE_ENABLED (1) set, param2/param3 are
  PX4's custom main/sub mode as QGroundControl sends them (main 1 Manual, 2 Altitude, 3 Position, 5 Acro,
  7 Stabilized, 8 Rattitude; main 4 Auto with sub 2 Takeoff, 3 Hold, 4 Mission, 5 Return, 6 Land; a NaN
  sub mode reads as 0); without it the base-mode flags are read as PX4 does (auto → Mission, manual input
  with guided → Position, with stabilize → Stabilized, else Manual).
* SET_NAV_STATE (100001, PX4-internal): param1 is the nav_state itself — the stack's simple mode id.
* NAV_TAKEOFF (22): param7 the takeoff altitude AMSL, or NaN for MIS_TAKEOFF_ALT above home; our
  extension: param2 = 1 makes param7 metres above home; the altitude above home must lie in MIS_TAKEOFF_ALT's
  range. param4 yaw [deg] (NaN keeps the heading). Like PX4's ``commander takeoff`` it arms the vehicle when
  disarmed. Only from the ground.
* NAV_LAND (21), NAV_RETURN_TO_LAUNCH (20), NAV_LOITER_UNLIM (17, Hold): mode changes; Land and Return
  need the vehicle armed (they forbid arming).
* DO_REPOSITION (192): go to param5/param6 latitude/longitude [deg] and param7 altitude AMSL [m] (each NaN
  keeps the current value), yaw param4 [deg], ground speed param1 [m/s] (≤ 0 or NaN: default); switches to
  Hold. Our extension DO_REPOSITION_LOCAL (100192, PX4-internal id range): the same with param5/6/7 the
  local north, east, down [m]. Refused when not flying, beyond MIS_DIST_1WP from home horizontally or
  vertically, lower than NAV_MC_ALT_RAD above home, or outside the geofence.
* MISSION_START (300): param1 first item (−1: current); needs a valid mission; arms when disarmed.
* DO_SET_MISSION_CURRENT (224): param1 the item to fly next (−1: keep; with param2 = 1, "reset", the first
  item); needs a valid mission; in Mission mode the vehicle goes there at once, otherwise when the mission next
  starts or resumes.
* INJECT_FAILURE (420): param1 the MAVLink FAILURE_UNIT, param2 the FAILURE_TYPE; accepted when
  SYS_FAILURE_EN is 1 (the simulator acts on it, as PX4's simulated sensors do), denied otherwise.

Modes follow PX4's rules: disarmed, any mode may be selected (except Land/Return, which could not arm);
armed, only a mode whose requirements are met, and a manual mode (Manual, Stabilized, Acro, Rattitude, Altitude,
Position) only with manual control input present (COM_RC_LOSS_T); Takeoff only from the ground; Mission only
with a mission. Yaw parameters are headings: within ±360° or NaN.
Home is set from the local position when one first appears on the ground, and again on arming.
Takeoff ends in Hold (COM_TAKEOFF_ACT 0) or Mission (1) once within NAV_MC_ALT_RAD of the takeoff
altitude — a fixed-wing vehicle's within NAV_FW_ALT_RAD, or within half the takeoff altitude when that is
less (as PX4 guards a multicopter's takeoff: a low takeoff altitude must not end the takeoff on the runway).
Auto-disarm: COM_DISARM_LAND seconds after landing (not mid-mission), COM_DISARM_PRFLT seconds after arming
without taking off. The command link counts as lost COM_DL_LOSS_T seconds after the last
ground-station/companion message, once one has been seen.

The vehicle type is MAV_TYPE's (:func:`~stack.commander.modes.vehicle_type_from_mav_type`), taken while
disarmed (a change made armed waits for the disarm, as PX4's commander does): it decides the modes the vehicle
has (a plane has neither Rattitude nor the RotorS mode; switching to one is denied with that reason), their
requirements and control flags (:mod:`stack.commander.modes`), the airspeed pre-arm check, the control chain
watched (:mod:`stack.commander.control_chain`) and ``vehicle_status.vehicle_type``/``system_type``.

With COM_EXT_AP the plant is an external autopilot (a PX4 Pixhawk the ``pixhawk`` module flies through,
see :mod:`stack.pixhawk.plant`): arming also needs it connected and armable; the commander arms, holds the
arming command's acknowledgement until the autopilot reports itself armed (``external_autopilot_status``),
and if the autopilot refuses, or has not armed within EXTERNAL_ARM_TIMEOUT_US, disarms and refuses the
command with the autopilot's reason. The autopilot's own arming state is the truth: when it disarms, the
commander disarms.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import replace
from enum import IntEnum
from typing import NamedTuple

from stack.commander.auto_disarm import AutoDisarm, AutoDisarmParams
from stack.commander.command_checks import (
    addressed_to,
    arm_action,
    arm_forced,
    goto_refusal,
    takeoff_altitude_refusal,
)
from stack.commander.commands import TAKEOFF_ALTITUDE_RELATIVE
from stack.commander.control_chain import CHAIN, FW_CHAIN, ChainFault, ControlChainMonitor, Loss
from stack.commander.failsafe import ACTION_NAMES, Failsafe, FailsafeAction, FailsafeConditions, FailsafeParams
from stack.commander.geofence import CylinderGeofence, GeofenceParams
from stack.commander.health import (
    CommanderInputs,
    HealthParams,
    arming_denial,
    can_run,
    external_autopilot_connected,
    failing_requirements,
    first_missing,
    manual_control_present,
    vehicle_type_name,
)
from stack.commander.home import HomePosition, home_from_local_position
from stack.commander.host_loss import HostLoss
from stack.commander.modes import (
    FIXED_WING,
    MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
    MODES,
    ROTARY_WING,
    Requirement,
    control_mode,
    mode_name,
    nav_state_from_base_mode,
    nav_state_from_custom_mode,
    valid_nav_states_mask,
    vehicle_type_from_mav_type,
)
from stack.mathlib.geo import MapProjection
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import (
    ActuatorArmed,
    VehicleCommand,
    VehicleCommandAck,
    VehicleControlMode,
    VehicleStatus,
    command_label,
)
from stack.params.binding import ParamSet
from stack.params.param import Param

NS = VehicleStatus
CMD = VehicleCommand
ACK = VehicleCommandAck

VEHICLE_CMD_SET_NAV_STATE = CMD.VEHICLE_CMD_SET_NAV_STATE
VEHICLE_CMD_DO_REPOSITION_LOCAL = CMD.VEHICLE_CMD_DO_REPOSITION_LOCAL
PREFLIGHT_CHECK_PERIOD_US = 100_000
EXTERNAL_ARM_TIMEOUT_US = 1_500_000
"""How long the external autopilot has to confirm an arming (a stack command's answer waits for it)."""
_POSITION_KNOWN = int(Requirement.LOCAL_POSITION_RELAXED | Requirement.LOCAL_ALT)
_ESTIMATES = (
    Requirement.ANGULAR_VELOCITY
    | Requirement.ATTITUDE
    | Requirement.LOCAL_POSITION
    | Requirement.LOCAL_POSITION_RELAXED
    | Requirement.LOCAL_ALT
)
EXTERNAL_LINK_GRACE_US = 1_500_000
"""After the external autopilot's link comes back, its sensors have this long to make the estimates valid."""
_POSITION_AND_ALTITUDE = int(Requirement.LOCAL_POSITION | Requirement.LOCAL_ALT)


class CommanderParams(ParamSet):
    """What the state machine reads itself (the health checks' among them), and its failsafe's and geofence's."""

    com_dl_loss_t: int
    com_rc_loss_t: float
    com_takeoff_act: int
    com_pos_fs_eph: float
    com_arm_wo_gps: int
    sys_has_baro: int
    sys_has_mag: int
    sys_has_gps: int
    sys_failure_en: int
    mis_takeoff_alt: float
    nav_mc_alt_rad: float
    com_ext_ap: int
    mis_dist_1wp: float
    mav_sys_id: int
    mav_comp_id: int
    mav_type: int
    nav_fw_alt_rad: float
    sys_has_num_aspd: int
    fw_airspd_max: float
    auto_disarm: AutoDisarmParams
    failsafe: FailsafeParams
    geofence: GeofenceParams


PARAMS: tuple[Param, ...] = CommanderParams.PARAMS


OWN_STALL_US = 250_000
"""A commander that did not run for this long (its process stopped, or starved on a loaded machine) has not
been reading its inputs either: what they tell is not judged until it has caught up."""
CATCH_UP_US = 300_000
"""How long after such a stall the commander takes its inputs' age and the chain's silence as its own."""


class ArmDisarmReason(IntEnum):
    """``vehicle_status.latest_arming_reason`` / ``latest_disarming_reason`` (PX4 ``arm_disarm_reason_t``)."""

    TRANSITION_TO_STANDBY = 0
    RC_STICK = 1
    RC_SWITCH = 2
    COMMAND_INTERNAL = 3
    COMMAND_EXTERNAL = 4
    MISSION_START = 5
    AUTO_DISARM_LAND = 7
    AUTO_DISARM_PREFLIGHT = 8
    FAILSAFE = 15


class NavigationRequest(NamedTuple):
    """What the commander asks the navigation glue to fly, beyond the mode itself."""

    takeoff_altitude: float
    """Takeoff target above home [m]."""
    takeoff_yaw: float
    """Takeoff heading [rad]; NaN keeps the current heading."""
    reposition: tuple[float, float, float, float] | None
    """Last go-to target: local north, east, down [m] and yaw [rad] (NaN: keep heading)."""
    reposition_speed: float
    """Requested ground speed [m/s]; NaN for the default."""
    reposition_counter: int
    """Increments with every accepted go-to."""
    mission_start_index: int
    """First item of the last mission start (−1: continue from the current item)."""
    mission_start_counter: int


class CommanderOutputs(NamedTuple):
    vehicle_status: VehicleStatus
    vehicle_control_mode: VehicleControlMode
    actuator_armed: ActuatorArmed
    changed: bool
    """Something in the three messages changed: publish now (else PX4 republishes at 2 Hz)."""
    failsafe_action: str
    """Name of the failsafe action in force: none, warn, hold, rtl, land, descend, disarm, terminate, fallback_*."""
    failsafe_delayed_action: str
    """The action waiting out COM_FAIL_ACT_T in Hold ("none" when none)."""
    failsafe_cause: str
    """Why: gcs_connection_loss, battery_critical, geofence_breach, local_position_invalid... ("" when none)."""
    home: HomePosition | None
    navigation: NavigationRequest
    events: tuple[str, ...]
    """Human-readable notices since the last update (arming, mode changes, failsafes)."""
    acks: tuple[VehicleCommandAck, ...]
    """Acknowledgements held back by ``handle_command`` and decided since the last update."""


_Verdict = tuple[int, str, int]
"""(result, reason, offending parameter index) of a command handler."""
_ACCEPTED: _Verdict = (ACK.VEHICLE_CMD_RESULT_ACCEPTED, "", 0)


def _denied(reason: str, param: int = 0) -> _Verdict:
    return (ACK.VEHICLE_CMD_RESULT_DENIED, reason, param)


def _rejected(reason: str) -> _Verdict:
    return (ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED, reason, 0)


def _finite_or_nan(value: float) -> bool:
    return math.isfinite(value) or math.isnan(value)


MAX_YAW_DEG = 360.0
"""Largest heading magnitude [deg] a command may give (MAVLink's yaw parameters are headings)."""


def _yaw_refusal(what: str, value: float) -> _Verdict | None:
    """Refusal of a yaw parameter (param4) that is neither NaN ("keep the heading") nor a heading in degrees."""
    if math.isnan(value) or (math.isfinite(value) and abs(value) <= MAX_YAW_DEG):
        return None
    return _denied(f"{what}: yaw (param4) must be within ±{MAX_YAW_DEG:g}° or NaN, got {value:g}", 4)


def _flag_refusal(what: str, index: int, value: float) -> _Verdict | None:
    """Refusal of a flag parameter that is neither a finite number nor NaN (not given)."""
    if _finite_or_nan(value):
        return None
    return _denied(f"{what}: param{index} must be finite or NaN, got {value:g}", index)


def _finite_position(lpos: VehicleLocalPosition) -> bool:
    return math.isfinite(lpos.x) and math.isfinite(lpos.y) and math.isfinite(lpos.z)


class Commander:
    """PX4's commander as a pure state machine (see the module docstring for the rules)."""

    def __init__(
        self, params: Mapping[str, object] | None = None, initial_nav_state: int = NS.NAVIGATION_STATE_MANUAL
    ) -> None:
        self._inputs = CommanderInputs()
        self.vehicle_type = ROTARY_WING
        """``vehicle_status.vehicle_type``, from MAV_TYPE (``mav_type``) while disarmed."""
        self.mav_type = CommanderParams().mav_type
        self._failsafe = Failsafe()
        self._geofence = CylinderGeofence()
        self._health = HealthParams()
        self.arming_state = NS.ARMING_STATE_DISARMED
        self.user_intended_nav_state = initial_nav_state
        self.nav_state = initial_nav_state
        self._intention_updated = False
        self._nav_state_timestamp_us = 0
        self._armed_time_us = 0
        self._takeoff_time_us = 0
        self._have_taken_off = False
        self._latest_arming_reason = 0
        self._latest_disarming_reason = 0
        self._home: HomePosition | None = None
        self._failing = Requirement.NONE
        self._last_step_us = 0
        self._catching_up_until_us = 0
        self._preflight_ok = False
        self._preflight_checked: tuple[int, int, int, int] | None = None
        self._preflight_checked_us = 0
        self._gcs_lost = False
        self._manual_control_lost = False
        self.chain = ControlChainMonitor()
        self.hosts: HostLoss | None = None
        """The vehicle's other hosts, when it is spread over several and flies in real time (:meth:`watch_hosts`)."""
        self._chain_faults: tuple[ChainFault, ...] = ()
        self._gcs_lost_counter = 0
        self.ignored_commands = 0
        self._command_time_us = 0
        """Commands addressed to another system or component, dropped unanswered."""
        self._geofence_violation = ""
        self._failsafe_action = FailsafeAction.NONE
        self._failsafe_delayed = FailsafeAction.NONE
        self._failsafe_cause = ""
        self._failsafe_takeover = False
        self._auto_disarm = AutoDisarm()
        self._takeoff_altitude = math.nan
        self._takeoff_yaw = math.nan
        self._reposition: tuple[float, float, float, float] | None = None
        self._reposition_speed = math.nan
        self._reposition_counter = 0
        self._mission_start_index = 0
        self._mission_start_counter = 0
        self._events: list[str] = []
        self._acks: list[VehicleCommandAck] = []
        self._external_arming: tuple[int, int] | None = None
        """(since µs, the autopilot's refusal count then) while its arming is awaited."""
        self._held_acks: list[VehicleCommandAck] = []
        self._external_armed_at = 0
        self._external_link_up_at: int | None = None
        """When the external autopilot's link (last) came up; None while it is down."""
        self._published_key: tuple | None = None
        self._can_set: dict[tuple[int, int], int] = {}
        """``can_set_nav_states_mask`` by vehicle type and failing requirements, which change rarely."""
        self._messages: tuple[VehicleStatus, VehicleControlMode, ActuatorArmed] | None = None
        self.set_params(params or {})
        self._takeoff_altitude = self._p.mis_takeoff_alt

    # ------------------------------------------------------------------ configuration and state

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = p = CommanderParams.from_params(params)
        self._auto_disarm.set_params(p.auto_disarm)
        self._failsafe.set_params(params)
        self._geofence.set_params(params)
        self._health = replace(HealthParams.from_params(params), vehicle_type=self.vehicle_type)
        self._take_vehicle_type()

    def _take_vehicle_type(self) -> None:
        """Take MAV_TYPE's vehicle type, unless armed (then it waits for the disarm)."""
        mav_type = self._p.mav_type
        if self.armed or mav_type == self.mav_type:
            return
        self.mav_type = mav_type
        vehicle_type = vehicle_type_from_mav_type(mav_type)
        if vehicle_type == self.vehicle_type:
            return
        self.vehicle_type = vehicle_type
        self._failsafe.vehicle_type = vehicle_type
        self._health = replace(self._health, vehicle_type=vehicle_type)
        self.chain.use(FW_CHAIN if vehicle_type == FIXED_WING else CHAIN)
        self._preflight_checked = None

    @property
    def armed(self) -> bool:
        return self.arming_state == NS.ARMING_STATE_ARMED

    @property
    def home(self) -> HomePosition | None:
        return self._home

    @property
    def failsafe_action(self) -> str:
        return ACTION_NAMES[self._failsafe_action]

    @property
    def failsafe_cause(self) -> str:
        return self._failsafe_cause

    def can_run(self, nav_state: int) -> bool:
        """Whether the vehicle has the mode and its requirements are met now."""
        return can_run(nav_state, self._failing, self.vehicle_type)

    # ------------------------------------------------------------------ cycle

    def update(self, now_us: int, inputs: CommanderInputs) -> CommanderOutputs:
        """One commander cycle with the latest inputs; returns what to publish."""
        self._inputs = inputs
        self._step(now_us)
        return self._outputs()

    def set_inputs(self, now_us: int, inputs: CommanderInputs) -> None:
        """Take the latest inputs before handling this cycle's commands (``update`` then runs the cycle),
        so a command is judged on what is known now, not at the previous cycle."""
        self._inputs = inputs
        self._failing = failing_requirements(now_us, inputs, self._health, self._home is not None)

    def addressed_to_me(self, cmd: VehicleCommand) -> bool:
        """Whether ``cmd`` is for this vehicle's autopilot (MAV_SYS_ID, MAV_COMP_ID, or 0 for all)."""
        return addressed_to(cmd, self._p.mav_sys_id, self._p.mav_comp_id)

    def handle_command(self, cmd: VehicleCommand, now_us: int) -> VehicleCommandAck | None:
        """Execute a ``vehicle_command`` and return its acknowledgement, or None when it is addressed to another
        system or component (ignored and counted in ``ignored_commands``, as PX4 does) or waits for the external
        autopilot to arm (its answer then comes out of ``update`` as one of ``acks``)."""
        if not self.addressed_to_me(cmd):
            self.ignored_commands += 1
            return None
        self._command_time_us = now_us
        handler = COMMAND_HANDLERS.get(cmd.command)
        awaiting = self._external_arming
        if handler is None:
            unsupported = f"Unsupported command {command_label(cmd.command)}"
            result, reason, param = (ACK.VEHICLE_CMD_RESULT_UNSUPPORTED, unsupported, 0)
        else:
            result, reason, param = handler(self, cmd, now_us)
        if result == ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            self._step(now_us)
        elif reason:
            self._events.append(reason)
        ack = VehicleCommandAck(
            timestamp=now_us,
            command=cmd.command,
            result=result,
            result_param2=param,
            target_system=cmd.source_system,
            target_component=cmd.source_component,
            from_external=False,
            reason=reason,
        )
        if awaiting is None and self._external_arming is not None:
            self._held_acks.append(ack)  # this command armed the stack: answer once the autopilot has armed
            return None
        return ack

    def _step(self, now_us: int) -> None:
        inp = self._inputs
        p = self._p
        lpos = inp.local_position
        if self._last_step_us and now_us - self._last_step_us > OWN_STALL_US:
            self._catching_up_until_us = now_us + CATCH_UP_US
            self._events.append(f"Commander stalled for {(now_us - self._last_step_us) / 1e6:.1f} s: catching up")
        self._last_step_us = now_us
        failing = failing_requirements(now_us, inp, self._health, self._home is not None)
        catching_up = now_us < self._catching_up_until_us
        # Inputs older than the stall are not the modules' fault: only what failed before it still fails.
        self._failing = failing & self._failing if catching_up else failing
        position_known = not int(self._failing) & _POSITION_KNOWN
        armed = self.armed

        if armed and not inp.landed and not self._have_taken_off:
            self._have_taken_off = True
            self._takeoff_time_us = now_us
        if self._home is None and position_known and inp.landed and lpos is not None and _finite_position(lpos):
            self._set_home(lpos)
            self._failing &= ~Requirement.HOME

        self._update_link(now_us)
        self._update_manual_control(now_us)
        hosts_held = False
        if self.hosts is not None:
            heard = {h: self.chain.last_output_us(modules) for h, modules in self.hosts.remote_flight_hosts.items()}
            self._events.extend(self.hosts.update(now_us, heard))
            hosts_held = armed and self.hosts.holding(now_us, estimates_valid=not self._failing & _ESTIMATES)
        if self._p.com_ext_ap:
            self._follow_external_autopilot(now_us)
            armed = self.armed
        self._geofence_violation = ""
        if armed and self._home is not None and self._geofence.enabled and position_known and lpos is not None:
            self._geofence_violation = self._geofence.violation(self._home.position, lpos.x, lpos.y, lpos.z)

        if (
            armed
            and not inp.landed
            and self.user_intended_nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
            and self.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF
            and self._takeoff_reached()
        ):
            follow = NS.NAVIGATION_STATE_AUTO_LOITER
            if p.com_takeoff_act == 1 and self.can_run(NS.NAVIGATION_STATE_AUTO_MISSION):
                follow = NS.NAVIGATION_STATE_AUTO_MISSION
            self._events.append(f"Takeoff complete, switching to {mode_name(follow)}")
            self._set_intention(follow)

        if not catching_up:
            self._update_control_chain(now_us, armed, hosts_held)
        if not armed and inp.landed and self._failsafe.selected_action == FailsafeAction.TERMINATE:
            # Disarmed by force while still falling, or before the land detector agreed: once it is on the
            # ground the vehicle may fly again, as after a disarm on the ground.
            self._clear_termination()
        failing = self._failing
        if self._external_link_down(now_us) or hosts_held:
            failing &= ~_ESTIMATES  # the estimates went with the link or host; the plant's own failsafe flies
        conditions = FailsafeConditions(
            failing=failing,
            gcs_connection_lost=self._gcs_lost,
            manual_control_lost=self._manual_control_lost,
            battery_warning=inp.battery_warning,
            geofence_breached=bool(self._geofence_violation),
            attitude_control_lost=any(f.loss == Loss.ATTITUDE_CONTROL for f in self._chain_faults),
            position_control_lost=any(f.loss == Loss.POSITION_CONTROL for f in self._chain_faults),
            airspeed_lost=any(f.loss == Loss.AIRSPEED for f in self._chain_faults),
            landed=inp.landed,
            host_lost=self.hosts is not None and self.hosts.flight_host_lost,
        )
        result = self._failsafe.update(
            now_us, armed, self.user_intended_nav_state, self._intention_updated, conditions, p.geofence.gf_action
        )
        self._intention_updated = False
        self._note_failsafe(result.action, result.delayed_action, result.cause, result.user_takeover)
        if result.action == FailsafeAction.DISARM and armed:
            self._disarm(now_us, ArmDisarmReason.FAILSAFE, forced=True)
        if result.nav_state != self.nav_state:
            self.nav_state = result.nav_state
            self._nav_state_timestamp_us = now_us

        self._update_auto_disarm(now_us)
        # PX4 Commander.cpp runs the arming checks at 10 Hz, and at once when the state changed.
        intended = self.user_intended_nav_state
        checked = (self.arming_state, intended, self.nav_state, int(self._failing))
        if checked != self._preflight_checked or now_us - self._preflight_checked_us >= PREFLIGHT_CHECK_PERIOD_US:
            self._preflight_checked = checked
            self._preflight_checked_us = now_us
            self._preflight_ok = not arming_denial(now_us, intended, self._failing, inp, self._health)

    # ------------------------------------------------------------------ resuming after a restart

    def kept_state(self) -> dict[str, object]:
        """What a commander restarted after a crash resumes from (see :meth:`resume`)."""
        return {
            "armed": self.armed,
            "armed_time_us": self._armed_time_us,
            "takeoff_time_us": self._takeoff_time_us,
            "have_taken_off": self._have_taken_off,
            "intended_nav_state": self.user_intended_nav_state,
            "home": list(self._home) if self._home is not None else None,
            "terminated": self._failsafe.selected_action == FailsafeAction.TERMINATE,
        }

    def resume(self, kept: Mapping[str, object], now_us: int) -> None:
        """Take over the vehicle as the crashed commander left it: armed (no checks: it is flying), in the mode the
        user chose, with the same home. Raises ValueError if ``kept`` is not what :meth:`kept_state` wrote."""
        intended, home = kept.get("intended_nav_state"), kept.get("home")
        armed_time, takeoff_time = kept.get("armed_time_us"), kept.get("takeoff_time_us")
        if not isinstance(intended, int) or intended not in MODES:
            raise ValueError(f"no known mode in {kept!r}")
        if not isinstance(armed_time, int) or not isinstance(takeoff_time, int):
            raise ValueError(f"no arming times in {kept!r}")
        if home is not None and (not isinstance(home, list) or len(home) != len(HomePosition._fields)):
            raise ValueError(f"no home position in {kept!r}")
        if home is not None:
            self._home = HomePosition(*(float(v) for v in home))
        self.user_intended_nav_state = self.nav_state = intended
        self._nav_state_timestamp_us = now_us
        if kept.get("armed") is True:
            self.arming_state = NS.ARMING_STATE_ARMED
            self._armed_time_us, self._takeoff_time_us = armed_time, takeoff_time
            self._have_taken_off = kept.get("have_taken_off") is True
        if kept.get("terminated") is True:
            self._failsafe.latch_termination()
            self.nav_state = NS.NAVIGATION_STATE_TERMINATION
        armed = "armed" if self.armed else "disarmed"
        self._events.append(f"Commander restarted: resuming {armed} in {mode_name(self.nav_state)}")

    def watch_hosts(
        self, placement: Mapping[str, Sequence[str]], own: str, lease_ms: int, outside: Collection[str]
    ) -> None:
        """The vehicle runs on several hosts (``placement``: host → its modules; ``own``: this one's), in real
        time: feed :attr:`hosts` with their beats (see :mod:`stack.commander.host_loss`)."""
        self.hosts = HostLoss(placement, own, lease_ms, outside)

    def _update_control_chain(self, now_us: int, armed: bool, hosts_held: bool) -> None:
        if self.nav_state == NS.NAVIGATION_STATE_TERMINATION:
            return  # terminated: the loops are off, and the modules that were lost stay named
        if self._p.com_ext_ap or hosts_held:
            # an external autopilot flies the vehicle, or the plant's side does while a host of the flight is missing
            self._chain_faults = ()
            return
        faults = tuple(self.chain.update(now_us, armed, control_mode(self.nav_state, armed, self.vehicle_type)))
        for fault in faults:
            if fault not in self._chain_faults:
                self._events.append(fault.describe())
        if self._chain_faults and not faults and armed:
            self._events.append("Control chain complete again")
        self._chain_faults = faults

    def _update_link(self, now_us: int) -> None:
        last = self._inputs.last_gcs_heartbeat_us
        lost = last > 0 and now_us - last > self._p.com_dl_loss_t * 1_000_000
        if lost and not self._gcs_lost:
            self._gcs_lost_counter += 1
            self._events.append("Connection to ground station lost")
        elif self._gcs_lost and not lost:
            self._events.append("Data link regained")
        self._gcs_lost = lost

    def _manual_control_present(self, now_us: int) -> bool:
        return manual_control_present(now_us, self._inputs, self._p.com_rc_loss_t)

    def _update_manual_control(self, now_us: int) -> None:
        """Manual control input counts as lost when it is no longer present, once some has been seen (PX4
        ``ManualControl.cpp``, ``rcAndDataLinkCheck.cpp``); never seen, it is a mode requirement, no failsafe."""
        lost = self._inputs.last_manual_control_us > 0 and not self._manual_control_present(now_us)
        if lost and not self._manual_control_lost:
            self._events.append("Manual control lost")
        elif self._manual_control_lost and not lost:
            self._events.append("Manual control regained")
        self._manual_control_lost = lost

    def _external_link_down(self, now_us: int) -> bool:
        """Armed with COM_EXT_AP, and the external autopilot's link is down or has just come back: its sensors,
        hence the stack's estimates, are missing, and its own failsafe (COM_OF_LOSS_T) flies the vehicle."""
        if not (self._p.com_ext_ap and self.armed):
            return False
        up_at = self._external_link_up_at
        return up_at is None or now_us - up_at < EXTERNAL_LINK_GRACE_US

    def _follow_external_autopilot(self, now_us: int) -> None:
        """Await the external autopilot's arming, follow it when it disarms on its own, note its link."""
        ext = self._inputs.external_autopilot
        connected = external_autopilot_connected(now_us, ext)
        if connected and self._external_link_up_at is None:
            self._external_link_up_at = now_us
            if self.armed:
                self._events.append("Link to the Pixhawk regained")
        elif not connected and self._external_link_up_at is not None:
            self._external_link_up_at = None
            if self.armed:
                self._events.append(
                    "Link to the Pixhawk lost: its own failsafe flies the vehicle (estimate failsafes held)"
                )
        awaiting = self._external_arming
        if awaiting is not None:
            since, refusals = awaiting
            if not self.armed:
                self._answer_held(
                    ACK.VEHICLE_CMD_RESULT_CANCELLED, "Arming cancelled: disarmed before the Pixhawk armed"
                )
            elif ext is not None and ext.timestamp >= since and ext.armed and ext.in_control:
                self._external_arming = None
                self._external_armed_at = ext.timestamp
                self._events.append(f"Pixhawk armed in {ext.mode}")
                self._answer_held(ACK.VEHICLE_CMD_RESULT_ACCEPTED, "")
            elif ext is not None and ext.refusals > refusals:
                self._refuse_external(now_us, f"Arming denied: {ext.refusal}")
            elif now_us - since > EXTERNAL_ARM_TIMEOUT_US:
                why = "no link" if not external_autopilot_connected(now_us, ext) else "no confirmation"
                self._refuse_external(
                    now_us, f"Arming denied: the Pixhawk did not arm within {EXTERNAL_ARM_TIMEOUT_US / 1e6:g} s ({why})"
                )
        elif self.armed and ext is not None and ext.timestamp > self._external_armed_at and not ext.armed:
            self._disarm(now_us, ArmDisarmReason.COMMAND_EXTERNAL, forced=True)
            self._events.append(f"The Pixhawk disarmed on its own (in {ext.mode}): disarmed")

    def _refuse_external(self, now_us: int, reason: str) -> None:
        self._disarm(now_us, ArmDisarmReason.COMMAND_EXTERNAL, forced=True)
        self._events.append(reason)
        self._answer_held(ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED, reason)

    def _answer_held(self, result: int, reason: str) -> None:
        self._external_arming = None
        for ack in self._held_acks:
            self._acks.append(
                VehicleCommandAck(
                    timestamp=ack.timestamp,
                    command=ack.command,
                    result=result,
                    target_system=ack.target_system,
                    target_component=ack.target_component,
                    reason=reason,
                )
            )
        self._held_acks.clear()

    def _takeoff_reached(self) -> bool:
        lpos = self._inputs.local_position
        if lpos is None or self._home is None or int(self._failing) & int(Requirement.LOCAL_ALT):
            return False
        target_z = self._home.z - self._takeoff_altitude
        if self.vehicle_type == FIXED_WING:
            acceptance = min(self._p.nav_fw_alt_rad, self._takeoff_altitude / 2.0)
        else:
            acceptance = self._p.nav_mc_alt_rad
        return lpos.z <= target_z + acceptance

    def _note_failsafe(self, action: FailsafeAction, delayed: FailsafeAction, cause: str, takeover: bool) -> None:
        if action != self._failsafe_action or delayed != self._failsafe_delayed:
            if delayed > FailsafeAction.WARN:
                delay = self._p.failsafe.com_fail_act_t
                self._events.append(
                    f"Failsafe activated ({cause}): entering Hold for {delay:g} s, then {ACTION_NAMES[delayed]}"
                )
            elif action > FailsafeAction.WARN:
                self._events.append(f"Failsafe activated ({cause}): {ACTION_NAMES[action]}")
            elif action == FailsafeAction.WARN and not takeover:
                self._events.append(f"Failsafe warning ({cause})")
            elif self._failsafe_action > FailsafeAction.WARN:
                self._events.append("Failsafe cleared" if not takeover else "User took over from the failsafe")
        self._failsafe_action = action
        self._failsafe_delayed = delayed
        self._failsafe_cause = cause
        self._failsafe_takeover = takeover

    def _update_auto_disarm(self, now_us: int) -> None:
        if not self.armed:
            self._auto_disarm.reset()
            return
        inp = self._inputs
        amid_mission = self.nav_state == NS.NAVIGATION_STATE_AUTO_MISSION and not inp.mission_finished
        if self._auto_disarm.update(now_us, inp.landed, self._have_taken_off, hold_landed=amid_mission):
            reason = ArmDisarmReason.AUTO_DISARM_LAND if self._have_taken_off else ArmDisarmReason.AUTO_DISARM_PREFLIGHT
            self._disarm(now_us, reason, forced=False)

    # ------------------------------------------------------------------ arming and modes

    def _set_home(self, lpos: VehicleLocalPosition) -> None:
        self._home = home_from_local_position(
            lpos.x, lpos.y, lpos.z, lpos.heading, lpos.ref_lat, lpos.ref_lon, lpos.ref_alt
        )
        self._events.append(f"Home set at N {lpos.x:.1f} m, E {lpos.y:.1f} m, D {lpos.z:.1f} m")

    def _arm(self, now_us: int, reason: ArmDisarmReason, forced: bool, prechecked: bool = False) -> str:
        """Arm after the pre-arm checks (skipped when ``forced`` or already passed); returns the refusal."""
        if self.armed:
            return ""
        if self._failsafe.selected_action == FailsafeAction.TERMINATE:
            return "Arming denied: flight termination is latched"
        if not forced and not prechecked:
            denial = arming_denial(now_us, self.user_intended_nav_state, self._failing, self._inputs, self._health)
            if denial:
                return denial
        self.arming_state = NS.ARMING_STATE_ARMED
        self._armed_time_us = now_us
        self._takeoff_time_us = 0
        self._have_taken_off = False
        self._latest_arming_reason = int(reason)
        self._auto_disarm.reset()
        lpos = self._inputs.local_position
        position_known = not int(self._failing) & _POSITION_KNOWN
        if position_known and lpos is not None:
            self._set_home(lpos)  # without a position now, the home set before stays, as in PX4
        self._events.append("Armed (forced: pre-arm checks skipped)" if forced else "Armed")
        if self._p.com_ext_ap:
            ext = self._inputs.external_autopilot
            self._external_arming = (now_us, ext.refusals if ext is not None else 0)
        return ""

    def _disarm(self, now_us: int, reason: ArmDisarmReason, forced: bool) -> str:
        if not self.armed:
            return ""
        on_ground = self._inputs.landed or self._inputs.maybe_landed
        if not forced and not on_ground:
            return "Disarming denied: not landed"
        self.arming_state = NS.ARMING_STATE_DISARMED
        if on_ground and self._failsafe.selected_action == FailsafeAction.TERMINATE:
            self._clear_termination()
        self._armed_time_us = 0
        self._takeoff_time_us = 0
        self._have_taken_off = False
        self._latest_disarming_reason = int(reason)
        self._auto_disarm.reset()
        self._events.append(f"Disarmed ({reason.name.lower()})")
        self._take_vehicle_type()
        return ""

    def _clear_termination(self) -> None:
        self._failsafe.clear_termination()
        self._events.append("Flight termination cleared: disarmed on the ground")

    def _set_intention(self, nav_state: int) -> None:
        self.user_intended_nav_state = nav_state
        self._intention_updated = True

    def _mode_refusal(self, nav_state: int) -> _Verdict | None:
        """Why switching to ``nav_state`` is refused now, or None (PX4 ``UserModeIntention::change``)."""
        mode = MODES.get(nav_state)
        if mode is None or not mode.user_selectable:
            return _denied(f"Unsupported mode (nav_state {nav_state})", 1)
        if not mode.available(self.vehicle_type):
            return _denied(f"{mode.name} mode is not available on {vehicle_type_name(self.vehicle_type)}", 1)
        prefix = f"Switching to {mode.name} is currently not possible"
        if nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF and self.armed and not self._inputs.landed:
            return _rejected(f"{prefix}: already flying")
        if nav_state in (NS.NAVIGATION_STATE_AUTO_RTL, NS.NAVIGATION_STATE_AUTO_LAND) and not self.armed:
            return _rejected(f"{prefix}: the vehicle is disarmed")
        if nav_state == NS.NAVIGATION_STATE_AUTO_MISSION and self._failing & Requirement.MISSION:
            return _rejected(f"{prefix}: no valid mission")
        if self.armed and not self.can_run(nav_state):
            return _rejected(f"{prefix}: requires {first_missing(nav_state, self._failing, self.vehicle_type)}")
        if (
            self.armed
            and mode.requirements & Requirement.MANUAL_CONTROL
            and not self._manual_control_present(self._command_time_us)
        ):
            return _rejected(f"{prefix}: no manual control input")
        return None

    def _change_mode(self, nav_state: int) -> _Verdict:
        refusal = self._mode_refusal(nav_state)
        if refusal is not None:
            return refusal
        if nav_state != self.user_intended_nav_state:
            self._events.append(f"Mode: {mode_name(nav_state)}")
            if nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
                self._takeoff_altitude = self._p.mis_takeoff_alt
                self._takeoff_yaw = math.nan
        self._set_intention(nav_state)
        return _ACCEPTED

    def _mode_and_arm(self, nav_state: int, now_us: int, reason: ArmDisarmReason) -> _Verdict:
        """Switch to ``nav_state`` and arm if needed, or change nothing."""
        refusal = self._mode_refusal(nav_state)
        if refusal is not None:
            return refusal
        if not self.armed:
            denial = arming_denial(now_us, nav_state, self._failing, self._inputs, self._health)
            if not denial and self._failsafe.selected_action == FailsafeAction.TERMINATE:
                denial = "Arming denied: flight termination is latched"
            if denial:
                return _rejected(denial)
        self._change_mode(nav_state)
        if not self.armed:
            self._arm(now_us, reason, forced=False, prechecked=True)
        return _ACCEPTED

    # ------------------------------------------------------------------ command handlers

    def _cmd_arm_disarm(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        action = arm_action(cmd.param1)
        if action is None:
            return _denied(f"Arm/disarm: param1 must be 1 (arm) or 0 (disarm), got {cmd.param1:g}", 1)
        refusal = _flag_refusal("Arm/disarm", 2, cmd.param2)
        if refusal is not None:
            return refusal
        forced = arm_forced(cmd.param2)
        reason = ArmDisarmReason.COMMAND_EXTERNAL if cmd.from_external else ArmDisarmReason.COMMAND_INTERNAL
        if action == CMD.ARMING_ACTION_ARM:
            refusal = self._arm(now_us, reason, forced=forced)
        else:
            refusal = self._disarm(now_us, reason, forced=forced)
        return _rejected(refusal) if refusal else _ACCEPTED

    def _cmd_set_mode(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        base = cmd.param1
        if not math.isfinite(base) or not 0 <= base <= 255:
            return _denied(f"Set mode: base mode (param1) must be 0–255, got {base:g}", 1)
        if int(base) & MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            main = cmd.param2
            sub = 0.0 if math.isnan(cmd.param3) else cmd.param3
            if not math.isfinite(main):
                return _denied(f"Set mode: custom main mode (param2) must be a number, got {main:g}", 2)
            if not math.isfinite(sub):
                return _denied(f"Set mode: custom sub mode (param3) must be a number, got {sub:g}", 3)
            nav_state = nav_state_from_custom_mode(round(main), round(sub))
            if nav_state is None:
                return _denied(f"Set mode: unknown or unsupported PX4 mode (main {main:g}, sub {sub:g})", 2)
        else:
            nav_state = nav_state_from_base_mode(int(base))
            if nav_state is None:
                return _denied(f"Set mode: base mode {int(base)} names no flight mode", 1)
        return self._change_mode(nav_state)

    def _cmd_set_nav_state(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        value = cmd.param1
        if not math.isfinite(value) or value != round(value) or round(value) not in MODES:
            return _denied(f"Set mode: unknown mode id {value:g}", 1)
        return self._change_mode(round(value))

    def _ground_altitude_amsl(self) -> float:
        """Altitude AMSL [m] of home when armed, else of the vehicle now (NaN without a reference)."""
        if self.armed and self._home is not None:
            return self._home.alt
        lpos = self._inputs.local_position
        return lpos.ref_alt - lpos.z if lpos is not None else math.nan

    def _cmd_takeoff(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        refusal = _yaw_refusal("Takeoff", cmd.param4) or _flag_refusal("Takeoff", 2, cmd.param2)
        if refusal is not None:
            return refusal
        altitude = cmd.param7
        relative = math.isfinite(cmd.param2) and round(cmd.param2) == TAKEOFF_ALTITUDE_RELATIVE
        if math.isnan(altitude):
            altitude = self._p.mis_takeoff_alt
        elif not math.isfinite(altitude):
            return _denied(f"Takeoff: altitude (param7) must be finite, got {altitude:g}", 7)
        elif not relative:
            ground = self._ground_altitude_amsl()
            if not math.isfinite(ground):
                return _denied("Takeoff: altitude given AMSL but the local frame has no altitude reference", 7)
            altitude -= ground
        out_of_range = takeoff_altitude_refusal(altitude)
        if out_of_range:
            return _denied(out_of_range, 7)
        ceiling = self._geofence.max_ver_dist
        if ceiling > 0.0 and altitude > ceiling:
            return _denied(f"Takeoff: {altitude:.1f} m above home is beyond GF_MAX_VER_DIST {ceiling:g} m", 7)
        verdict = self._mode_and_arm(NS.NAVIGATION_STATE_AUTO_TAKEOFF, now_us, reason=self._command_reason(cmd))
        if verdict[0] == ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            self._takeoff_altitude = altitude
            self._takeoff_yaw = math.radians(cmd.param4) if math.isfinite(cmd.param4) else math.nan
        return verdict

    @staticmethod
    def _command_reason(cmd: VehicleCommand) -> ArmDisarmReason:
        return ArmDisarmReason.COMMAND_EXTERNAL if cmd.from_external else ArmDisarmReason.COMMAND_INTERNAL

    def _check_reposition_params(self, cmd: VehicleCommand) -> _Verdict | None:
        for index, value in ((1, cmd.param1), (5, cmd.param5), (6, cmd.param6), (7, cmd.param7)):
            if not _finite_or_nan(value):
                return _denied(f"Reposition: param{index} must be finite or NaN, got {value:g}", index)
        return _yaw_refusal("Reposition", cmd.param4)

    def _cmd_reposition_global(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        refusal = self._check_reposition_params(cmd)
        if refusal is not None:
            return refusal
        lat, lon = cmd.param5, cmd.param6
        if math.isnan(lat) != math.isnan(lon):
            return _denied("Reposition: give both latitude (param5) and longitude (param6), or neither", 5)
        if math.isfinite(lat) and not (-90.0 <= lat <= 90.0):
            return _denied(f"Reposition: latitude {lat:g} is outside ±90°", 5)
        if math.isfinite(lon) and not (-180.0 <= lon <= 180.0):
            return _denied(f"Reposition: longitude {lon:g} is outside ±180°", 6)
        lpos = self._inputs.local_position
        north = east = down = math.nan
        if math.isfinite(lat):
            if lpos is None or not (math.isfinite(lpos.ref_lat) and math.isfinite(lpos.ref_lon)):
                return _denied("Reposition: the local frame has no global reference for latitude/longitude", 5)
            north, east = MapProjection(lpos.ref_lat, lpos.ref_lon).project(lat, lon)
        if math.isfinite(cmd.param7):
            if lpos is None or not math.isfinite(lpos.ref_alt):
                return _denied("Reposition: the local frame has no altitude reference for an AMSL altitude", 7)
            down = lpos.ref_alt - cmd.param7
        return self._reposition_to(north, east, down, cmd)

    def _cmd_reposition_local(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        refusal = self._check_reposition_params(cmd)
        if refusal is not None:
            return refusal
        return self._reposition_to(cmd.param5, cmd.param6, cmd.param7, cmd)

    def _reposition_to(self, north: float, east: float, down: float, cmd: VehicleCommand) -> _Verdict:
        """Go to the local target (NaN components keep the current position) after the state checks."""
        lpos = self._inputs.local_position
        if not self.armed or self._inputs.landed:
            return _rejected("Reposition denied: the vehicle is not flying")
        if lpos is None or int(self._failing) & _POSITION_AND_ALTITUDE:
            return _rejected("Reposition denied: no valid local position estimate")
        if self._home is None:
            return _rejected("Reposition denied: no home position")
        altitude_given = not math.isnan(down)
        north = lpos.x if math.isnan(north) else north
        east = lpos.y if math.isnan(east) else east
        down = lpos.z if math.isnan(down) else down
        if not (math.isfinite(north) and math.isfinite(east) and math.isfinite(down)):
            return _rejected("Reposition denied: no valid local position estimate")
        home = self._home.position
        too_far, param = goto_refusal(
            home,
            (north, east, down),
            altitude_given,
            self._p.mis_dist_1wp,
            self._p.nav_mc_alt_rad,
        )
        if too_far:
            return _denied(too_far, param)
        violation = self._geofence.violation(home, north, east, down)
        if violation:
            return _denied(f"Reposition denied: target outside the geofence ({violation})", 5)
        verdict = self._change_mode(NS.NAVIGATION_STATE_AUTO_LOITER)
        if verdict[0] != ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            return verdict
        yaw = math.radians(cmd.param4) if math.isfinite(cmd.param4) else math.nan
        self._reposition = (north, east, down, yaw)
        self._reposition_speed = cmd.param1 if math.isfinite(cmd.param1) and cmd.param1 > 0.0 else math.nan
        self._reposition_counter += 1
        self._events.append(f"Going to N {north:.1f} m, E {east:.1f} m, D {down:.1f} m")
        return _ACCEPTED

    def _cmd_mission_start(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        count = self._inputs.mission_count
        if count <= 0:
            return _denied("Mission start denied: no valid mission")
        first = cmd.param1
        if not math.isfinite(first) or first != round(first) or not -1 <= first < count:
            return _denied(f"Mission start: first item (param1) must be −1…{count - 1}, got {first:g}", 1)
        verdict = self._mode_and_arm(NS.NAVIGATION_STATE_AUTO_MISSION, now_us, ArmDisarmReason.MISSION_START)
        if verdict[0] == ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            self._mission_start_index = round(first)
            self._mission_start_counter += 1
        return verdict

    def _cmd_set_mission_current(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        count = self._inputs.mission_count
        if count <= 0:
            return _denied("Set current mission item denied: no valid mission")
        refusal = _flag_refusal("Set current mission item", 2, cmd.param2)
        if refusal is not None:
            return refusal
        seq, reset = cmd.param1, math.isfinite(cmd.param2) and round(cmd.param2) == 1
        if math.isnan(seq) or seq == -1:
            if not reset:
                return _ACCEPTED
            seq = 0.0
        if not math.isfinite(seq) or seq != round(seq) or not 0 <= seq < count:
            return _denied(f"Set current mission item: param1 must be −1…{count - 1}, got {seq:g}", 1)
        self._mission_start_index = round(seq)
        self._mission_start_counter += 1
        self._events.append(f"Mission: item {round(seq)} is next")
        return _ACCEPTED

    def _cmd_inject_failure(self, cmd: VehicleCommand, now_us: int) -> _Verdict:
        if not self._p.sys_failure_en:
            return _denied("Failure injection is disabled (SYS_FAILURE_EN 0)")
        for index, value in ((1, cmd.param1), (2, cmd.param2)):
            if not math.isfinite(value) or value != round(value) or value < 0:
                return _denied(f"Failure injection: param{index} must be a non-negative integer, got {value:g}", index)
        self._events.append(f"Failure injected: unit {round(cmd.param1)}, type {round(cmd.param2)}")
        return _ACCEPTED

    # ------------------------------------------------------------------ outputs

    def _outputs(self) -> CommanderOutputs:
        armed = self.armed
        failing = int(self._failing)
        vehicle_type = self.vehicle_type
        can_set = self._can_set.get((vehicle_type, failing))
        if can_set is None:
            can_set = sum(1 << state for state in MODES if can_run(state, self._failing, vehicle_type))
            self._can_set[vehicle_type, failing] = can_set
        key = (
            self.arming_state,
            self.nav_state,
            self.user_intended_nav_state,
            self._nav_state_timestamp_us,
            self._armed_time_us,
            self._takeoff_time_us,
            self._latest_arming_reason,
            self._latest_disarming_reason,
            self._failsafe_action > FailsafeAction.WARN,
            self._failsafe_takeover,
            self._gcs_lost,
            self._gcs_lost_counter,
            self._preflight_ok,
            can_set,
            self._chain_faults,
            self.mav_type,
            tuple(self.hosts.lost) if self.hosts is not None else (),
        )
        changed = key != self._published_key
        if changed or self._messages is None:
            self._published_key = key
            terminated = self.nav_state == NS.NAVIGATION_STATE_TERMINATION
            status = VehicleStatus(
                system_id=self._p.mav_sys_id,
                component_id=self._p.mav_comp_id,
                armed_time=self._armed_time_us,
                takeoff_time=self._takeoff_time_us,
                arming_state=self.arming_state,
                latest_arming_reason=self._latest_arming_reason,
                latest_disarming_reason=self._latest_disarming_reason,
                nav_state_timestamp=self._nav_state_timestamp_us,
                nav_state_user_intention=self.user_intended_nav_state,
                nav_state=self.nav_state,
                valid_nav_states_mask=valid_nav_states_mask(vehicle_type),
                can_set_nav_states_mask=can_set,
                failsafe=self._failsafe_action > FailsafeAction.WARN,
                failsafe_and_user_took_over=self._failsafe_takeover,
                gcs_connection_lost=self._gcs_lost,
                gcs_connection_lost_counter=self._gcs_lost_counter,
                pre_flight_checks_pass=self._preflight_ok,
                control_lost_modules=[f.module for f in self._chain_faults],
                lost_hosts=list(self.hosts.lost) if self.hosts is not None else [],
                vehicle_type=vehicle_type,
                system_type=self.mav_type,
            )
            actuator_armed = ActuatorArmed(
                armed=armed,
                prearmed=armed,
                ready_to_arm=self._preflight_ok or armed,
                lockdown=terminated,
                termination=terminated,
            )
            self._messages = (status, control_mode(self.nav_state, armed, vehicle_type), actuator_armed)
        events = tuple(self._events)
        self._events.clear()
        acks = tuple(self._acks)
        self._acks.clear()
        status, mode, actuator_armed = self._messages
        return CommanderOutputs(
            vehicle_status=status,
            vehicle_control_mode=mode,
            actuator_armed=actuator_armed,
            changed=changed,
            failsafe_action=ACTION_NAMES[self._failsafe_action],
            failsafe_delayed_action=ACTION_NAMES[self._failsafe_delayed],
            failsafe_cause=self._failsafe_cause,
            home=self._home,
            navigation=NavigationRequest(
                takeoff_altitude=self._takeoff_altitude,
                takeoff_yaw=self._takeoff_yaw,
                reposition=self._reposition,
                reposition_speed=self._reposition_speed,
                reposition_counter=self._reposition_counter,
                mission_start_index=self._mission_start_index,
                mission_start_counter=self._mission_start_counter,
            ),
            events=events,
            acks=acks,
        )


def _mode_command(nav_state: int) -> Callable[[Commander, VehicleCommand, int], _Verdict]:
    def handler(commander: Commander, cmd: VehicleCommand, now_us: int) -> _Verdict:
        return commander._change_mode(nav_state)

    return handler


COMMAND_HANDLERS: dict[int, Callable[[Commander, VehicleCommand, int], _Verdict]] = {
    CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM: Commander._cmd_arm_disarm,
    CMD.VEHICLE_CMD_DO_SET_MODE: Commander._cmd_set_mode,
    VEHICLE_CMD_SET_NAV_STATE: Commander._cmd_set_nav_state,
    CMD.VEHICLE_CMD_NAV_TAKEOFF: Commander._cmd_takeoff,
    CMD.VEHICLE_CMD_NAV_LAND: _mode_command(NS.NAVIGATION_STATE_AUTO_LAND),
    CMD.VEHICLE_CMD_NAV_RETURN_TO_LAUNCH: _mode_command(NS.NAVIGATION_STATE_AUTO_RTL),
    CMD.VEHICLE_CMD_NAV_LOITER_UNLIM: _mode_command(NS.NAVIGATION_STATE_AUTO_LOITER),
    CMD.VEHICLE_CMD_DO_REPOSITION: Commander._cmd_reposition_global,
    VEHICLE_CMD_DO_REPOSITION_LOCAL: Commander._cmd_reposition_local,
    CMD.VEHICLE_CMD_MISSION_START: Commander._cmd_mission_start,
    CMD.VEHICLE_CMD_DO_SET_MISSION_CURRENT: Commander._cmd_set_mission_current,
    CMD.VEHICLE_CMD_INJECT_FAILURE: Commander._cmd_inject_failure,
}
"""How the commander carries out each ``vehicle_command`` it supports (PX4 ``Commander::handle_command``)."""
SUPPORTED_COMMANDS = frozenset(COMMAND_HANDLERS)
"""The ``vehicle_command`` ids the commander carries out; any other is answered UNSUPPORTED."""
