"""Health and arming checks: which estimates and sensors are usable, and whether arming is allowed.

After PX4 ``HealthAndArmingChecks`` (``estimatorCheck``, ``sensor checks``, ``batteryCheck``, ``modeCheck``):
the result is the set of mode requirements that currently fail (so "can mode X run" is one mask test, against
the vehicle type's requirements, :mod:`stack.commander.modes`) and,
for arming, the first reason in PX4's spirit ("Arming denied: ..."):

* the mode forbids arming (Return, Land, Descend, Termination);
* gyro and accelerometer data, and barometer / magnetometer data when SYS_HAS_BARO / SYS_HAS_MAG, are
  fresh (younger than 1 s);
* the angular velocity and the attitude estimate are fresh and the attitude quaternion is a unit
  quaternion — whatever the mode;
* the mode's own requirements (a valid local position for Position and the auto modes, an altitude
  estimate, a mission);
* a 3-D GPS fix when SYS_HAS_GPS and either COM_ARM_WO_GPS = 0 or the mode needs a position;
* a fixed-wing vehicle's airspeed (PX4 ``airspeedCheck.cpp``, unless SYS_HAS_NUM_ASPD is 0): the airspeed
  sensor's data fresh, the validated airspeed (``airspeed_validated``, the airspeed selector's) fresh and
  finite, and not above FW_AIRSPD_MAX (a badly calibrated sensor, or a wind no flight could make headway in);
* the battery warning is below CRITICAL (PX4: LOW only warns);
* with COM_EXT_AP, the external autopilot (a Pixhawk the stack flies through) is connected, and armable
  if it is in Offboard already.

Validity: the attitude and angular velocity are valid when updated within 1 s; the local position is
valid when updated within 1 s with ``xy_valid`` and ``v_xy_valid`` set and ``eph`` (when reported) below
COM_POS_FS_EPH; "relaxed" drops the velocity and accuracy conditions; the altitude needs ``z_valid``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

from stack.commander.modes import (
    FIXED_WING,
    MODES,
    REQUIREMENT_CAUSE,
    REQUIREMENT_TEXT,
    ROTARY_WING,
    RUN_REQUIREMENTS,
    Requirement,
)
from stack.mathlib.quaternion import IDENTITY, Quat
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.sensors import SensorGps
from stack.msg.system import BatteryWarning, ExternalAutopilotStatus
from stack.params.binding import ParamSet

ESTIMATE_TIMEOUT_US = 1_000_000
SENSOR_TIMEOUT_US = 1_000_000
EXTERNAL_AUTOPILOT_TIMEOUT_US = 1_000_000
QUATERNION_NORM_TOLERANCE = 0.05


@dataclass(slots=True)
class CommanderInputs:
    """The latest values the commander reads; the module glue copies them from their topics.

    Timestamps are the receive/publication times of the last message (0 = never). ``landed`` and
    ``maybe_landed`` come from ``vehicle_land_detected``; ``battery_warning`` from ``battery_status``;
    ``last_gcs_heartbeat_us`` is the time of the last report of a ground station's HEARTBEAT (MAV_TYPE_GCS;
    the command link); ``last_manual_control_us`` the time of the last valid manual control input (sticks from a
    radio, a joystick or a ground station) and ``manual_control_valid`` whether the latest one is valid;
    ``mission_count`` is the number of items of the loaded, valid mission (0: none) and
    ``mission_finished`` whether its last item has been reached; ``airspeed_timestamp_us`` is the last
    ``airspeed`` (the sensor), ``airspeed_validated_timestamp_us`` and ``calibrated_airspeed`` the last
    ``airspeed_validated`` (NaN: invalid).
    """

    attitude_timestamp_us: int = 0
    attitude_q: Quat = IDENTITY
    angular_velocity_timestamp_us: int = 0
    local_position: VehicleLocalPosition | None = None
    gyro_timestamp_us: int = 0
    accel_timestamp_us: int = 0
    baro_timestamp_us: int = 0
    mag_timestamp_us: int = 0
    gps_timestamp_us: int = 0
    gps_fix_type: int = 0
    landed: bool = True
    maybe_landed: bool = True
    battery_warning: int = BatteryWarning.NONE
    last_gcs_heartbeat_us: int = 0
    last_manual_control_us: int = 0
    manual_control_valid: bool = False
    mission_count: int = 0
    mission_finished: bool = False
    external_autopilot: ExternalAutopilotStatus | None = None
    """The external autopilot the stack flies through (``external_autopilot_status``), when there is one."""
    airspeed_timestamp_us: int = 0
    airspeed_validated_timestamp_us: int = 0
    calibrated_airspeed: float = math.nan


class HealthParams(ParamSet):
    """The checks' parameters (the catalogue's: the sensors fitted, COM_ARM_WO_GPS, COM_POS_FS_EPH, COM_EXT_AP,
    FW_AIRSPD_MAX) and the vehicle type they apply to."""

    sys_has_baro: int
    sys_has_mag: int
    sys_has_gps: int
    com_arm_wo_gps: int
    com_pos_fs_eph: float
    com_ext_ap: int
    sys_has_num_aspd: int
    fw_airspd_max: float
    vehicle_type: int = ROTARY_WING
    """``vehicle_status.vehicle_type`` (from MAV_TYPE)."""


def _fresh(now_us: int, stamp_us: int, timeout_us: int) -> bool:
    return stamp_us > 0 and now_us - stamp_us < timeout_us


def manual_control_present(now_us: int, inp: CommanderInputs, loss_timeout_s: float) -> bool:
    """Whether manual control input (sticks) is present: the latest is valid and the last valid one at most
    COM_RC_LOSS_T old (PX4 ``ManualControl.cpp``); what the modes that need it require (PX4
    ``mode_req_manual_control`` against ``manual_control_signal_lost``)."""
    last = inp.last_manual_control_us
    return last > 0 and inp.manual_control_valid and now_us - last <= loss_timeout_s * 1e6


_AV = int(Requirement.ANGULAR_VELOCITY)
_ATT = int(Requirement.ATTITUDE)
_POS = int(Requirement.LOCAL_POSITION)
_POS_RELAXED = int(Requirement.LOCAL_POSITION_RELAXED)
_ALT = int(Requirement.LOCAL_ALT)
_MISSION = int(Requirement.MISSION)
_HOME = int(Requirement.HOME)
# Plain-int masks: IntFlag arithmetic and construction cost about a microsecond per operation.
_RUN_MASKS: dict[int, dict[int, int]] = {
    vehicle_type: {
        state: int(m.requirements_for(vehicle_type) & RUN_REQUIREMENTS)
        for state, m in MODES.items()
        if m.available(vehicle_type)
    }
    for vehicle_type in (ROTARY_WING, FIXED_WING)
}
_PREVENTS_ARMING = frozenset(s for s, m in MODES.items() if m.requirements & Requirement.PREVENT_ARMING)
_REQUIREMENT_ORDER: tuple[tuple[int, Requirement], ...] = tuple((int(r), r) for r in REQUIREMENT_TEXT)
_as_requirement = cache(Requirement)


def failing_requirements(now_us: int, inp: CommanderInputs, params: HealthParams, home_valid: bool) -> Requirement:
    """The run requirements that are not met now (PX4 ``failsafe_flags`` ``*_invalid``)."""
    failing = 0
    if not _fresh(now_us, inp.angular_velocity_timestamp_us, ESTIMATE_TIMEOUT_US):
        failing |= _AV
    q = inp.attitude_q
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if not _fresh(now_us, inp.attitude_timestamp_us, ESTIMATE_TIMEOUT_US) or not (
        abs(norm - 1.0) < QUATERNION_NORM_TOLERANCE
    ):
        failing |= _ATT
    lpos = inp.local_position
    if lpos is None or not _fresh(now_us, lpos.timestamp, ESTIMATE_TIMEOUT_US):
        failing |= _POS | _POS_RELAXED | _ALT
    else:
        if not lpos.xy_valid:
            failing |= _POS | _POS_RELAXED
        elif not lpos.v_xy_valid or lpos.eph > params.com_pos_fs_eph:
            failing |= _POS
        if not lpos.z_valid:
            failing |= _ALT
    if inp.mission_count <= 0:
        failing |= _MISSION
    if not home_valid:
        failing |= _HOME
    return _as_requirement(failing)


def can_run(nav_state: int, failing: Requirement, vehicle_type: int = ROTARY_WING) -> bool:
    """Whether the vehicle type has the mode and its requirements are met."""
    mask = _RUN_MASKS[vehicle_type].get(nav_state)
    return mask is not None and not (mask & int(failing))


def missing_requirement(nav_state: int, failing: Requirement, vehicle_type: int = ROTARY_WING) -> Requirement:
    """The first run requirement of the mode that is not met (NONE if it can run)."""
    missing = _RUN_MASKS[vehicle_type].get(nav_state, 0) & int(failing)
    if missing:
        for bit, req in _REQUIREMENT_ORDER:
            if missing & bit:
                return req
    return Requirement.NONE


def first_missing(nav_state: int, failing: Requirement, vehicle_type: int = ROTARY_WING) -> str:
    """What the mode misses, e.g. "a valid local position estimate" ("" if it can run)."""
    return REQUIREMENT_TEXT.get(missing_requirement(nav_state, failing, vehicle_type), "")


def missing_cause(nav_state: int, failing: Requirement, vehicle_type: int = ROTARY_WING) -> str:
    """The failsafe cause name for what the mode misses, e.g. "local_position_invalid"."""
    return REQUIREMENT_CAUSE.get(missing_requirement(nav_state, failing, vehicle_type), "")


def vehicle_type_name(vehicle_type: int) -> str:
    return "a fixed-wing vehicle" if vehicle_type == FIXED_WING else "a rotary-wing vehicle"


def arming_denial(now_us: int, nav_state: int, failing: Requirement, inp: CommanderInputs, params: HealthParams) -> str:
    """Why arming in ``nav_state`` is refused now, or "" if the pre-arm checks pass.

    The mode's home requirement is left out: home is set on arming."""
    mode = MODES.get(nav_state)
    if mode is None:
        return f"Arming denied: nav_state {nav_state} is not a supported mode"
    vehicle_type = params.vehicle_type
    if not mode.available(vehicle_type):
        return f"Arming denied: {mode.name} mode is not available on {vehicle_type_name(vehicle_type)}"
    if nav_state in _PREVENTS_ARMING:
        return f"Arming denied: not possible in {mode.name} mode, switch mode first"
    needs_airspeed = vehicle_type == FIXED_WING and params.sys_has_num_aspd
    sensors = (
        ("gyro", inp.gyro_timestamp_us, True),
        ("accelerometer", inp.accel_timestamp_us, True),
        ("barometer", inp.baro_timestamp_us, params.sys_has_baro),
        ("magnetometer", inp.mag_timestamp_us, params.sys_has_mag),
        ("airspeed", inp.airspeed_timestamp_us, needs_airspeed),
    )
    for name, stamp, required in sensors:
        if required and not _fresh(now_us, stamp, SENSOR_TIMEOUT_US):
            return f"Arming denied: no {name} data"
    failing_bits = int(failing)
    if failing_bits & _AV:
        return "Arming denied: no angular velocity estimate"
    if failing_bits & _ATT:
        return "Arming denied: attitude estimate invalid"
    missing = first_missing(nav_state, _as_requirement(failing_bits & ~_HOME), vehicle_type)
    if missing:
        return f"Arming denied: {mode.name} mode requires {missing}"
    if needs_airspeed:
        denial = airspeed_denial(now_us, inp, params.fw_airspd_max)
        if denial:
            return denial
    needs_position = bool(_RUN_MASKS[vehicle_type][nav_state] & (_POS | _POS_RELAXED))
    if params.sys_has_gps and (needs_position or not params.com_arm_wo_gps):
        if not _fresh(now_us, inp.gps_timestamp_us, SENSOR_TIMEOUT_US):
            return "Arming denied: no GPS data"
        if inp.gps_fix_type < SensorGps.FIX_TYPE_3D:
            return "Arming denied: no 3D GPS fix"
    if inp.battery_warning >= BatteryWarning.EMERGENCY:
        return "Arming denied: battery at emergency level"
    if inp.battery_warning >= BatteryWarning.CRITICAL:
        return "Arming denied: battery critically low"
    if params.com_ext_ap:
        return external_autopilot_denial(now_us, inp.external_autopilot)
    return ""


def airspeed_denial(now_us: int, inp: CommanderInputs, airspeed_max: float) -> str:
    """PX4 ``airspeedCheck.cpp``: why the validated airspeed forbids arming ("" if it does not)."""
    if not _fresh(now_us, inp.airspeed_validated_timestamp_us, SENSOR_TIMEOUT_US):
        return "Arming denied: no validated airspeed (is airspeed_selector running?)"
    airspeed = inp.calibrated_airspeed
    if not math.isfinite(airspeed):
        return "Arming denied: airspeed invalid"
    if abs(airspeed) > airspeed_max:
        return f"Arming denied: airspeed too high ({airspeed:.1f} m/s, FW_AIRSPD_MAX {airspeed_max:g} m/s)"
    return ""


def external_autopilot_connected(now_us: int, ext: ExternalAutopilotStatus | None) -> bool:
    return ext is not None and ext.connected and _fresh(now_us, ext.timestamp, EXTERNAL_AUTOPILOT_TIMEOUT_US)


def external_autopilot_denial(now_us: int, ext: ExternalAutopilotStatus | None) -> str:
    """Why the external autopilot cannot be armed now ("" if it can, as far as the stack can tell).

    PX4's pre-arm check (SYS_STATUS) judges the mode it is in; it is arming in Offboard that counts, so the
    check is taken only there (in another mode the hand-off switches to Offboard first, and a refusal then
    comes with PX4's own reason)."""
    if not external_autopilot_connected(now_us, ext):
        return "Arming denied: no link to the external autopilot (Pixhawk)"
    assert ext is not None
    if ext.offboard and not ext.armable:
        return f"Arming denied: the Pixhawk's pre-arm checks fail in {ext.mode}"
    return ""
