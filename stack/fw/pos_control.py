"""Fixed-wing position control: the navigator's triplet or the pilot's sticks → roll, pitch, yaw and throttle.

PX4's ``fw_pos_control_l1`` (v1.13; ``FixedwingPositionControl.cpp``) in one I/O-free class:

* lateral guidance by L1 (seed 004, :class:`~stack.fw.l1_guidance.L1Guidance`) or NPFG
  (:class:`~stack.fw.npfg.NPFG`), chosen by FW_USE_NPFG: lines between waypoints, loiter circles and headings
  give a lateral acceleration, flown as the roll angle atan(a/g) within FW_R_LIM;
* longitudinal control by TECS (:class:`~stack.fw.tecs.Tecs`): altitude and airspeed setpoints give the
  pitch and throttle setpoints; the airspeed setpoint is kept above FW_AIRSPD_MIN (the landing's airspeed while
  landing) times √(load factor) of the bank commanded, as the stall speed rises in a turn (PX4 v1.14);
* per setpoint type: POSITION flies the line previous → current; LOITER the circle about current; TAKEOFF
  the runway takeoff (:class:`~stack.fw.runway_takeoff.RunwayTakeoff`: heading held on the wheels, rotation,
  climb-out along the runway's line); LAND the glide slope and PX4 v1.14's sink-rate flare
  (:class:`~stack.fw.landing.Landing`: TECS on a height rate, pitch and throttle limits ramped towards the flare's),
  then the roll-out on the wheels with the throttle at idle;
* Altitude mode: roll from the roll stick (FW_MAN_R_MAX), height rate from the pitch stick (up to
  FW_T_CLMB_MAX / FW_T_SINK_MAX), airspeed from the throttle stick (FW_AIRSPD_MIN…TRIM…MAX); Position mode
  the same, but with the roll stick centred it holds the line along the heading it had when the stick
  centred (PX4's heading hold);
* Descend (no position, or a failsafe): a gentle turning descent at FW_T_SINK_MIN on TECS, PX4's fixed-wing
  "descend" (NAV_GPSF_R bank).

Frames: local NED metres; TECS works on altitudes up (−z). The heading setpoint is the track's bearing (the
attitude controller's yaw is coordinated in flight; it only matters on the wheels).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.fw.l1_guidance import L1Guidance
from stack.fw.landing import Landing, LandingParams
from stack.fw.npfg import NPFG, NpfgParams
from stack.fw.runway_takeoff import RunwayTakeoff, RunwayTakeoffParams, RunwayTakeoffState
from stack.fw.tecs import Tecs, TecsParams
from stack.mathlib.scalar import FLT_EPSILON, constrain
from stack.mathlib.vector import Vec3
from stack.msg.fixedwing import PositionSetpoint, PositionSetpointTriplet
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus
from stack.params.binding import ParamSet
from stack.params.param import Param

NS = VehicleStatus
SP = PositionSetpoint
NAN = math.nan
Vec2 = tuple[float, float]

HEADING_HOLD_AHEAD = 3000.0
"""How far ahead Position mode's held line reaches [m] (PX4's HDG_HOLD_DIST_NEXT)."""
MANUAL_STICK_DEADZONE = 0.05
"""Sticks within this of centre count as centred (heading hold; no height rate)."""
DESCEND_BANK = math.radians(15.0)
"""The descent's bank angle (PX4 NAV_GPSF_R default)."""
TOUCHDOWN_HEIGHT = 0.3
"""Below this height over the landing point in the flare the aircraft is on its wheels, or about to be [m]."""
CLIMBOUT_PITCH_MIN = math.radians(10.0)
"""TECS' lower pitch limit during the climb-out (PX4 FW_P_LIM_MIN is the other bound)."""
SWITCH_DISTANCE_CAP = 500.0
"""The waypoint radius the guidance's switching distance is capped by (PX4 fw_pos_control: switch_distance(500)):
the navigator accepts a waypoint within the larger of this distance and the item's radius."""

class FwPosControlParams(ParamSet):
    """What the position controller reads itself, and its guidance's, TECS', runway takeoff's and landing's."""

    fw_use_npfg: int
    fw_l1_period: float
    fw_l1_damping: float
    fw_l1_r_slew_max: float
    fw_r_lim: float
    fw_p_lim_min: float
    fw_p_lim_max: float
    fw_thr_cruise: float
    fw_thr_min: float
    fw_thr_max: float
    fw_thr_idle: float
    fw_airspd_min: float
    fw_airspd_trim: float
    fw_airspd_max: float
    fw_man_r_max: float
    nav_acc_rad: float
    nav_loiter_rad: float
    tecs: TecsParams
    npfg: NpfgParams
    runway: RunwayTakeoffParams
    landing: LandingParams


PARAMS: tuple[Param, ...] = FwPosControlParams.PARAMS


class FwPosInputs(NamedTuple):
    now_us: int
    dt: float
    nav_state: int
    armed: bool
    landed: bool
    position: Vec3
    """Local NED [m]; NaN components when not known."""
    velocity: Vec3
    """NED [m/s]."""
    acceleration: Vec3
    """NED kinematic acceleration [m/s²]."""
    roll: float
    pitch: float
    yaw: float
    airspeed: float
    """Calibrated (≈ equivalent) airspeed [m/s]; NaN: no valid airspeed."""
    eas_to_tas: float
    wind: Vec2
    """Wind estimate NE [m/s]; NaN: none."""
    triplet: PositionSetpointTriplet | None
    manual: ManualControlSetpoint | None


class FwPosOutput(NamedTuple):
    roll: float
    pitch: float
    yaw: float
    throttle: float
    wheel_steering: bool
    reset_integral: bool


class GuidanceStatus(NamedTuple):
    """What ``position_controller_status`` reports."""

    nav_roll: float
    nav_pitch: float
    nav_bearing: float
    target_bearing: float
    xtrack_error: float
    wp_dist: float
    acceptance_radius: float
    type: int


def _xy(v: Vec3 | PositionSetpoint) -> Vec2:
    if isinstance(v, PositionSetpoint):
        return (v.x, v.y)
    return (v[0], v[1])


def _finite2(v: Vec2) -> bool:
    return math.isfinite(v[0]) and math.isfinite(v[1])


class FixedwingPositionControl:
    """``update(inputs)`` every position estimate returns the attitude and throttle setpoints (None: the mode
    is not one this controller flies, or the vehicle is disarmed)."""

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._p = FwPosControlParams()
        self._values: dict[str, object] = {}
        """The values given so far, by PX4 name (a later ``set_params`` may give only some)."""
        self.tecs = Tecs(self._p.tecs)
        self.l1 = L1Guidance()
        self.npfg = NPFG(self._p.npfg)
        self.runway = RunwayTakeoff(self._p.runway)
        self.landing = Landing(self._p.landing)
        self._mode_key: tuple[int, int] | None = None
        self._hold_line: tuple[Vec2, Vec2] | None = None
        self._hold_center: Vec3 | None = None
        self._landing_key: tuple[float, float, float, float] | None = None
        self._touched_down = False
        self._land_throttle = NAN
        self._altitude_hold = NAN
        self._roll_sp = 0.0
        self.status = GuidanceStatus(NAN, NAN, NAN, NAN, NAN, NAN, NAN, 0)
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._values.update(params)
        self._p = p = FwPosControlParams.from_params(self._values)
        self.tecs.set_params(p.tecs)
        self.npfg.set_params(p.npfg)
        self.runway.params = p.runway
        self.landing.set_params(p.landing)
        self.l1.set_l1_period(p.fw_l1_period)
        self.l1.set_l1_damping(p.fw_l1_damping)
        self.l1.roll_limit = math.radians(p.fw_r_lim)
        self.l1.roll_slew_rate = math.radians(p.fw_l1_r_slew_max)

    @property
    def uses_npfg(self) -> bool:
        return self._p.fw_use_npfg >= 0.5

    @property
    def guidance(self) -> L1Guidance | NPFG:
        return self.npfg if self.uses_npfg else self.l1

    # ------------------------------------------------------------------ cycle

    def update(self, inp: FwPosInputs) -> FwPosOutput | None:
        out = self._update(inp)
        self._roll_sp = out.roll if out is not None and math.isfinite(out.roll) else 0.0
        return out

    def _update(self, inp: FwPosInputs) -> FwPosOutput | None:
        if not inp.armed:
            self._mode_key = None
            self.tecs.reset()
            return None
        nav = inp.nav_state
        triplet = inp.triplet
        kind = triplet.current.type if triplet is not None and triplet.current.valid else -1
        key = (nav, kind)
        if key != self._mode_key:
            self._on_mode_change(inp, key)
            self._mode_key = key
        position_known = all(math.isfinite(c) for c in inp.position)
        if nav == NS.NAVIGATION_STATE_DESCEND or (nav in _AUTO and not position_known):
            return self._descend(inp)
        if not position_known:
            return None
        if nav == NS.NAVIGATION_STATE_ALTCTL:
            return self._manual(inp, hold_heading=False)
        if nav == NS.NAVIGATION_STATE_POSCTL:
            return self._manual(inp, hold_heading=True)
        if nav not in _AUTO:
            return None
        if triplet is None or not triplet.current.valid:
            if self._hold_center is None:
                self._hold_center = inp.position
            return self._loiter(inp, self._hold_center, self._p.nav_loiter_rad, 1)
        current = triplet.current
        if current.type == SP.SETPOINT_TYPE_TAKEOFF:
            return self._takeoff(inp, triplet)
        if current.type == SP.SETPOINT_TYPE_LAND:
            return self._land(inp, triplet)
        if current.type == SP.SETPOINT_TYPE_LOITER:
            radius = current.loiter_radius if math.isfinite(current.loiter_radius) else self._p.nav_loiter_rad
            direction = -1 if current.loiter_direction_counter_clockwise else 1
            return self._loiter(inp, (current.x, current.y, current.z), radius, direction)
        return self._waypoint(inp, triplet)

    def _on_mode_change(self, inp: FwPosInputs, key: tuple[int, int]) -> None:
        previous = self._mode_key
        self._hold_line = None
        self._hold_center = None
        self._altitude_hold = NAN
        if previous is None or previous[0] != key[0]:
            self.tecs.reset()
        if key[1] != SP.SETPOINT_TYPE_TAKEOFF:
            self.runway.reset()
        if key[1] != SP.SETPOINT_TYPE_LAND:
            self.landing.reset()
            self._landing_key = None
            self._touched_down = False
            self._land_throttle = NAN

    # ------------------------------------------------------------------ building blocks

    def _airspeed_sp(self, requested: float = NAN, minimum: float = NAN) -> float:
        """``requested`` (else FW_AIRSPD_TRIM) within the least airspeed and FW_AIRSPD_MAX. The least is ``minimum``
        (else FW_AIRSPD_MIN) raised as the stall speed rises in a turn, by the square root of the load factor
        1/cos(roll) of the bank last commanded (PX4 v1.14 ``FixedwingPositionControl::adapt_airspeed_setpoint``)."""
        p = self._p
        speed = requested if math.isfinite(requested) and requested > 0.0 else p.fw_airspd_trim
        least = minimum if math.isfinite(minimum) else p.fw_airspd_min
        least *= math.sqrt(1.0 / max(math.cos(self._roll_sp), FLT_EPSILON))
        return constrain(speed, min(least, p.fw_airspd_max), p.fw_airspd_max)

    def _tecs(
        self,
        inp: FwPosInputs,
        altitude_sp: float,
        airspeed_sp: float,
        *,
        height_rate_sp: float = NAN,
        pitch_min: float = NAN,
        pitch_max: float = NAN,
        throttle_min: float = NAN,
        throttle_max: float = NAN,
        climbout: bool = False,
        in_air: bool = True,
    ) -> tuple[float, float]:
        p = self._p
        pitch_min = pitch_min if math.isfinite(pitch_min) else math.radians(p.fw_p_lim_min)
        pitch_max = pitch_max if math.isfinite(pitch_max) else math.radians(p.fw_p_lim_max)
        throttle_min = throttle_min if math.isfinite(throttle_min) else p.fw_thr_min
        throttle_max = throttle_max if math.isfinite(throttle_max) else p.fw_thr_max
        vz = inp.velocity[2]
        out = self.tecs.update(
            inp.dt,
            altitude=-inp.position[2],
            vz=vz if math.isfinite(vz) else 0.0,
            vz_valid=math.isfinite(vz),
            az=inp.acceleration[2],
            airspeed=inp.airspeed,
            speed_derivative=_body_x_acceleration(inp),
            eas_to_tas=inp.eas_to_tas,
            pitch=inp.pitch,
            roll=inp.roll,
            altitude_sp=altitude_sp,
            airspeed_sp=airspeed_sp,
            pitch_min=pitch_min,
            pitch_max=pitch_max,
            throttle_min=throttle_min,
            throttle_max=throttle_max,
            throttle_trim=p.fw_thr_cruise,
            height_rate_sp=height_rate_sp,
            climbout=climbout,
            climbout_pitch_min=CLIMBOUT_PITCH_MIN,
            in_air=in_air,
        )
        return out.pitch_sp, out.throttle_sp

    def _ground_velocity(self, inp: FwPosInputs) -> Vec2:
        return (inp.velocity[0], inp.velocity[1])

    def _wind(self, inp: FwPosInputs) -> Vec2:
        return inp.wind if _finite2(inp.wind) else (0.0, 0.0)

    def _line(self, inp: FwPosInputs, a: Vec2, b: Vec2) -> float:
        """Follow A→B; the roll setpoint."""
        g = self.guidance
        position, velocity = _xy(inp.position), self._ground_velocity(inp)
        if g is self.npfg:
            self.npfg.set_airspeed_limits(
                self._p.fw_airspd_trim * _ratio(inp), self._p.fw_airspd_max * _ratio(inp)
            )
            self.npfg.navigate_waypoints(a, b, position, velocity, inp.dt, wind=self._wind(inp))
        else:
            self.l1.navigate_waypoints(a, b, position, velocity, inp.dt)
        return g.roll_setpoint

    def _circle(self, inp: FwPosInputs, center: Vec2, radius: float, direction: int) -> float:
        g = self.guidance
        position, velocity = _xy(inp.position), self._ground_velocity(inp)
        if g is self.npfg:
            self.npfg.set_airspeed_limits(
                self._p.fw_airspd_trim * _ratio(inp), self._p.fw_airspd_max * _ratio(inp)
            )
            self.npfg.navigate_loiter(center, position, radius, direction, velocity, inp.dt, wind=self._wind(inp))
        else:
            self.l1.navigate_loiter(center, position, radius, direction, velocity, inp.dt)
        return g.roll_setpoint

    def _heading(self, inp: FwPosInputs, heading: float) -> float:
        g = self.guidance
        velocity = self._ground_velocity(inp)
        if g is self.npfg:
            self.npfg.navigate_heading(heading, inp.yaw, velocity, inp.dt, wind=self._wind(inp))
        else:
            self.l1.navigate_heading(heading, inp.yaw, velocity, inp.dt)
        return g.roll_setpoint

    def _report(self, inp: FwPosInputs, target: Vec2, kind: int) -> None:
        g = self.guidance
        acceptance = g.switch_distance(SWITCH_DISTANCE_CAP)
        self.status = GuidanceStatus(
            nav_roll=g.roll_setpoint,
            nav_pitch=NAN,
            nav_bearing=g.nav_bearing,
            target_bearing=g.target_bearing,
            xtrack_error=g.crosstrack_error,
            wp_dist=math.hypot(target[0] - inp.position[0], target[1] - inp.position[1]),
            acceptance_radius=acceptance,
            type=kind,
        )

    def _track(self, inp: FwPosInputs) -> float:
        speed = math.hypot(inp.velocity[0], inp.velocity[1])
        return math.atan2(inp.velocity[1], inp.velocity[0]) if speed > 1.0 else inp.yaw

    # ------------------------------------------------------------------ auto setpoint types

    def _waypoint(self, inp: FwPosInputs, triplet: PositionSetpointTriplet) -> FwPosOutput:
        current = triplet.current
        b = _xy(current)
        a = _xy(triplet.previous) if triplet.previous.valid and _finite2(_xy(triplet.previous)) else _xy(inp.position)
        roll = self._line(inp, a, b)
        self._report(inp, b, current.type)
        pitch, throttle = self._tecs(inp, -current.z, self._airspeed_sp(current.cruising_speed))
        return FwPosOutput(roll, pitch, self._track(inp), throttle, False, False)

    def _loiter(self, inp: FwPosInputs, center: Vec3, radius: float, direction: int) -> FwPosOutput:
        roll = self._circle(inp, (center[0], center[1]), radius, direction)
        self._report(inp, (center[0], center[1]), SP.SETPOINT_TYPE_LOITER)
        altitude = -center[2] if math.isfinite(center[2]) else -inp.position[2]
        pitch, throttle = self._tecs(inp, altitude, self._airspeed_sp())
        return FwPosOutput(roll, pitch, self._track(inp), throttle, False, False)

    def _takeoff(self, inp: FwPosInputs, triplet: PositionSetpointTriplet) -> FwPosOutput:
        runway = self.runway
        current = triplet.current
        start = triplet.previous if triplet.previous.valid else None
        ground_z = start.z if start is not None and math.isfinite(start.z) else inp.position[2]
        if not runway.initialized:
            runway.init(inp.now_us, inp.yaw, _xy(inp.position))
        height = ground_z - inp.position[2]
        airspeed = inp.airspeed if math.isfinite(inp.airspeed) else 0.0
        state = runway.update(inp.now_us, airspeed, height, _xy(inp.position))
        target = _xy(current)
        if runway.wheel_steering:
            roll = 0.0
            self._report(inp, target, current.type)
        else:
            roll = runway.roll(self._line(inp, runway.start_position, target))
            self._report(inp, target, current.type)
        p = self._p
        pitch_sp, throttle_sp = self._tecs(
            inp,
            -current.z,
            self._airspeed_sp(),
            pitch_min=runway.min_pitch(CLIMBOUT_PITCH_MIN, math.radians(p.fw_p_lim_min)),
            pitch_max=runway.max_pitch(math.radians(p.fw_p_lim_max)),
            climbout=runway.climbout,
            in_air=state >= RunwayTakeoffState.TAKEOFF,
        )
        yaw = runway.yaw(self._track(inp))
        return FwPosOutput(
            roll,
            runway.pitch(pitch_sp),
            yaw,
            runway.throttle(inp.now_us, throttle_sp),
            runway.wheel_steering,
            runway.reset_integrators,
        )

    def _land(self, inp: FwPosInputs, triplet: PositionSetpointTriplet) -> FwPosOutput:
        current = triplet.current
        previous = triplet.previous if triplet.previous.valid and _finite2(_xy(triplet.previous)) else None
        key = (current.x, current.y, current.z, previous.x if previous is not None else NAN)
        if key != self._landing_key:
            self.landing.reset()
            self._landing_key = key
            self._touched_down = False
            self._land_throttle = NAN
        sp = self.landing.update(
            _xy(inp.position),
            -inp.position[2],
            _xy(current),
            -current.z,
            inp.yaw,
            _xy(previous) if previous is not None else None,
            -previous.z if previous is not None else NAN,
            now=inp.now_us * 1e-6,
            down_speed=inp.velocity[2],
            throttle=self._land_throttle,
        )
        p = self._p
        height = current.z - inp.position[2]
        if sp.flaring and (height < TOUCHDOWN_HEIGHT or inp.landed):
            self._touched_down = True
        # TECS' underspeed protection stays on in the flare, so that with the throttle going to idle the pitch
        # gives way to the airspeed before the wing stalls. PX4 v1.14 turns it off there
        # (FixedwingPositionControl.cpp: tecs_update_pitch_throttle(..., disable_underspeed_detection=true, ...)).
        pitch, throttle = self._tecs(
            inp,
            sp.altitude_sp,
            self._airspeed_sp(sp.airspeed_sp, min(p.fw_airspd_min, sp.airspeed_sp)),
            height_rate_sp=sp.height_rate_sp,
            pitch_min=sp.pitch_min,
            pitch_max=sp.pitch_max,
            throttle_min=sp.throttle_min,
            throttle_max=sp.throttle_max,
            in_air=not inp.landed,
        )
        if self._touched_down:
            # On the wheels, or just above them: idle, steered along the runway. The pitch stays the flare's (PX4
            # v1.14 flies it down to the ground): raising the nose of a vehicle still floating would stall it.
            self._report(inp, _xy(current), current.type)
            return FwPosOutput(0.0, pitch, sp.target_bearing, p.fw_thr_idle, True, True)
        roll = self._heading(inp, sp.target_bearing) if sp.heading_hold else self._line(inp, sp.track_a, sp.track_b)
        roll = constrain(roll, -sp.roll_limit, sp.roll_limit)
        self._report(inp, _xy(current), current.type)
        if sp.flaring:
            throttle = self.landing.flare_throttle(throttle)
        self._land_throttle = throttle
        return FwPosOutput(roll, pitch, sp.target_bearing, throttle, False, False)

    # ------------------------------------------------------------------ pilot and failsafe modes

    def _manual(self, inp: FwPosInputs, hold_heading: bool) -> FwPosOutput:
        p = self._p
        sticks = inp.manual
        roll_stick = sticks.roll if sticks is not None and sticks.valid else 0.0
        pitch_stick = sticks.pitch if sticks is not None and sticks.valid else 0.0
        throttle_stick = sticks.throttle if sticks is not None and sticks.valid else 0.0
        roll_stick, pitch_stick = _deadzone(roll_stick), _deadzone(pitch_stick)
        if hold_heading and roll_stick == 0.0:
            if self._hold_line is None:
                track = self._track(inp)
                start = _xy(inp.position)
                self._hold_line = (
                    start,
                    (start[0] + HEADING_HOLD_AHEAD * math.cos(track), start[1] + HEADING_HOLD_AHEAD * math.sin(track)),
                )
            roll = self._line(inp, *self._hold_line)
            self._report(inp, self._hold_line[1], SP.SETPOINT_TYPE_POSITION)
        else:
            self._hold_line = None
            roll = roll_stick * math.radians(p.fw_man_r_max)
        # Stick forward (+pitch) descends, back climbs (PX4 FW_POSCTL's height-rate stick).
        rate = -pitch_stick * (p.tecs.fw_t_sink_max if pitch_stick > 0.0 else p.tecs.fw_t_clmb_max)
        throttle01 = constrain(0.5 * (throttle_stick + 1.0), 0.0, 1.0)
        if throttle01 < 0.5:
            airspeed = p.fw_airspd_min + (p.fw_airspd_trim - p.fw_airspd_min) * throttle01 * 2.0
        else:
            airspeed = p.fw_airspd_trim + (p.fw_airspd_max - p.fw_airspd_trim) * (throttle01 - 0.5) * 2.0
        # Sticks centred: hold the altitude where the height rate went to zero.
        if rate != 0.0:
            self._altitude_hold = NAN
        elif not math.isfinite(self._altitude_hold):
            self._altitude_hold = -inp.position[2]
        pitch, throttle = self._tecs(inp, self._altitude_hold, airspeed, height_rate_sp=rate)
        return FwPosOutput(roll, pitch, self._track(inp), throttle, False, False)

    def _descend(self, inp: FwPosInputs) -> FwPosOutput:
        p = self._p
        if math.isfinite(inp.position[2]):
            pitch, throttle = self._tecs(inp, NAN, self._airspeed_sp(), height_rate_sp=-p.tecs.fw_t_sink_min)
        else:
            pitch, throttle = 0.0, p.fw_thr_cruise * 0.5
        return FwPosOutput(DESCEND_BANK, pitch, inp.yaw, throttle, False, False)


_AUTO = (
    NS.NAVIGATION_STATE_AUTO_TAKEOFF,
    NS.NAVIGATION_STATE_AUTO_LOITER,
    NS.NAVIGATION_STATE_AUTO_MISSION,
    NS.NAVIGATION_STATE_AUTO_RTL,
    NS.NAVIGATION_STATE_AUTO_LAND,
)


def _ratio(inp: FwPosInputs) -> float:
    return inp.eas_to_tas if math.isfinite(inp.eas_to_tas) and inp.eas_to_tas > 0.0 else 1.0


def _deadzone(stick: float) -> float:
    if not math.isfinite(stick) or abs(stick) < MANUAL_STICK_DEADZONE:
        return 0.0
    return constrain(stick, -1.0, 1.0)


def _body_x_acceleration(inp: FwPosInputs) -> float:
    """The kinematic acceleration along the body x axis (PX4 TECS' airspeed-rate input)."""
    cp = math.cos(inp.pitch)
    x_axis = (cp * math.cos(inp.yaw), cp * math.sin(inp.yaw), -math.sin(inp.pitch))
    value = sum(a * x for a, x in zip(inp.acceleration, x_axis, strict=True))
    return value if math.isfinite(value) else 0.0

