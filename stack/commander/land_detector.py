"""PX4's multicopter land detector: freefall, ground contact, maybe landed, landed, ground effect.

Follows ``src/modules/land_detector/MulticopterLandDetector.cpp`` and ``LandDetector.cpp`` (PX4 main):

* **ground contact** — low thrust (below MPC_THR_MIN + 30 % of the way to the hover thrust, 60 % while a
  hover-thrust estimate is valid), no vertical movement (|vz| or |dz/dt| below LNDMC_Z_VEL_MAX, 2.5 × that
  once landed), no horizontal movement (|v_xy| ≤ LNDMC_XY_VEL_MAX) and, in climb-rate-controlled modes,
  a commanded descent (velocity setpoint down ≥ 1.1 × LNDMC_Z_VEL_MAX) until maybe-landed is reached;
* **maybe landed** — thrust below MPC_THR_MIN + 10 % of the way to hover (MPC_MANTHR_MIN + 0.01 in
  manual-thrust modes), no freefall, roll/pitch rate below LNDMC_ROT_MAX (2.5 × once landed), and ground
  contact — or, without a vertical velocity estimate, minimum thrust held for 8 s;
* **landed** — maybe landed held once more.

Each of the three stages must hold for LNDMC_TRIG_TIME / 3 (three times longer while a range finder is
fitted but out of range), so the whole sequence takes LNDMC_TRIG_TIME (1 s) from touchdown. Older PX4
used fixed stage times (0.35 s, 0.25 s, 0.3 s); current PX4 derives all three from LNDMC_TRIG_TIME.
Disarmed, the vehicle is always landed. Freefall is a specific force below 2 m/s² for 0.3 s.

LNDMC_Z_VEL_MAX is 0.25 m/s in current PX4 (0.5 m/s before); like PX4 it is capped at
min(MPC_LAND_CRWL, MPC_LAND_SPEED) / 1.2 so that a landing descent is always seen as "moving".
``at_rest`` (landed with no measured motion) replaces PX4's IMU-vibration based flag.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

from stack.commander.hysteresis import Hysteresis
from stack.mathlib.vector import ZERO3, Vec3
from stack.msg.estimation import VehicleImuStatus, VehicleLocalPosition
from stack.msg.setpoints import (
    HoverThrustEstimate,
    TakeoffState,
    TakeoffStatus,
    TrajectorySetpoint,
    VehicleThrustSetpoint,
)
from stack.msg.system import VehicleStatus
from stack.params.binding import ParamSet
from stack.params.param import Param


class LandDetectorParams(ParamSet):
    """The detector's thresholds (LNDMC_*) and the position controller's thrust and landing speeds it judges by."""

    lndmc_trig_time: float
    lndmc_z_vel_max: float
    lndmc_xy_vel_max: float
    lndmc_rot_max: float
    lndmc_alt_gnd: float
    mpc_thr_min: float
    mpc_thr_hover: float
    mpc_manthr_min: float
    mpc_use_hte: bool
    mpc_land_speed: float
    mpc_land_crwl: float


PARAMS: tuple[Param, ...] = LandDetectorParams.PARAMS

PERIOD_US = 20_000
"""How often the detector runs (PX4 ``LandDetector.h``: LAND_DETECTOR_UPDATE_INTERVAL, 20 ms)."""
FREEFALL_SPECIFIC_FORCE = 2.0
"""Specific-force magnitude [m/s²] below which the vehicle is falling freely."""
FREEFALL_TRIGGER_TIME_US = 300_000
MINIMUM_THRUST_FALLBACK_US = 8_000_000
"""Minimum thrust held this long means landed when there is no vertical velocity estimate."""
POSITION_TIMEOUT_US = 1_000_000
HOVER_ESTIMATE_TIMEOUT_US = 1_000_000
DIST_FROM_GROUND_THRESHOLD = 1.0
"""Range-finder distance [m] below which ground contact is possible when a range finder is fitted."""
LANDED_WIDENING = 2.5
"""Thresholds are widened by this factor once landed, so spool-up vibration does not unland."""


@dataclass(slots=True)
class LandDetectorInputs:
    """The latest values of the land detector's inputs; the module glue copies them from topics.

    ``throttle`` is the collective thrust setpoint (−``vehicle_thrust_setpoint.xyz[2]``),
    ``acceleration`` the specific force (``vehicle_acceleration``), ``velocity_setpoint_z`` the
    ``trajectory_setpoint`` vertical velocity (NaN when not set), ``hover_thrust`` and
    ``hover_thrust_timestamp_us`` the last valid ``hover_thrust_estimate``.
    """

    armed: bool = False
    local_position_timestamp_us: int = 0
    z_valid: bool = False
    v_xy_valid: bool = False
    v_z_valid: bool = False
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    z_deriv: float = 0.0
    dist_bottom_valid: bool = False
    dist_bottom: float = 0.0
    dist_bottom_observable: bool = False
    angular_velocity: Vec3 = ZERO3
    acceleration: Vec3 = (0.0, 0.0, -9.80665)
    throttle: float = 0.0
    climb_rate_control: bool = False
    velocity_setpoint_z: float = math.nan
    hover_thrust: float = math.nan
    hover_thrust_timestamp_us: int = 0
    takeoff_state: int = TakeoffState.DISARMED


_TAKEOFF_STATES = frozenset(int(state) for state in TakeoffState)


def takeoff_state(value: int) -> TakeoffState | None:
    """The takeoff state a ``takeoff_status`` reports, or None for "uninitialized" or a value that names none
    (dropped: the land detector keeps the state it had)."""
    return TakeoffState(value) if value in _TAKEOFF_STATES else None


_NO_CLIMB_RATE_CONTROL = frozenset((
    VehicleStatus.NAVIGATION_STATE_MANUAL,
    VehicleStatus.NAVIGATION_STATE_STAB,
    VehicleStatus.NAVIGATION_STATE_ACRO,
    VehicleStatus.NAVIGATION_STATE_RATTITUDE,
    VehicleStatus.NAVIGATION_STATE_OFFBOARD,
    VehicleStatus.NAVIGATION_STATE_TERMINATION,  # no loop runs, nothing commands a descent
))


def climb_rate_controlled(nav_state: int) -> bool:
    """Whether a loop controls the climb rate in ``nav_state`` (PX4 reads ``flag_control_climb_rate_enabled``)."""
    return nav_state not in _NO_CLIMB_RATE_CONTROL


def throttle_in_mode(throttle: float, nav_state: int) -> float:
    """The thrust the detector counts: none in termination, where the motors are stopped whatever the controllers
    still ask."""
    return 0.0 if nav_state == VehicleStatus.NAVIGATION_STATE_TERMINATION else throttle


def multicopter_inputs(
    armed: bool,
    nav_state: int,
    lpos: VehicleLocalPosition | None,
    imu: VehicleImuStatus | None,
    thrust: VehicleThrustSetpoint | None,
    trajectory: TrajectorySetpoint | None,
    hover: HoverThrustEstimate | None,
    takeoff: TakeoffStatus | None,
) -> LandDetectorInputs:
    """The detector's inputs from the latest messages (None: none received), as ``MulticopterLandDetector.cpp``
    reads its topics."""
    inp = LandDetectorInputs()
    inp.armed = armed
    if lpos is not None:
        inp.local_position_timestamp_us = lpos.timestamp
        inp.z_valid, inp.v_xy_valid, inp.v_z_valid = lpos.z_valid, lpos.v_xy_valid, lpos.v_z_valid
        inp.vx, inp.vy, inp.vz, inp.z_deriv = lpos.vx, lpos.vy, lpos.vz, lpos.z_deriv
        inp.dist_bottom_valid, inp.dist_bottom = lpos.dist_bottom_valid, lpos.dist_bottom
    if imu is not None:
        inp.angular_velocity = imu.mean_gyro
        inp.acceleration = imu.mean_accel
    if thrust is not None:
        inp.throttle = -thrust.xyz[2]
    inp.throttle = throttle_in_mode(inp.throttle, nav_state)
    inp.climb_rate_control = climb_rate_controlled(nav_state)
    inp.velocity_setpoint_z = trajectory.velocity[2] if trajectory is not None else math.nan
    if hover is not None and hover.valid:
        inp.hover_thrust, inp.hover_thrust_timestamp_us = hover.hover_thrust, hover.timestamp
    state = takeoff_state(takeoff.takeoff_state) if takeoff is not None else None
    if state is not None:
        inp.takeoff_state = state
    return inp


class LandDetectorState(NamedTuple):
    """``vehicle_land_detected`` content (PX4 field names)."""

    freefall: bool
    ground_contact: bool
    maybe_landed: bool
    landed: bool
    in_ground_effect: bool
    in_descend: bool
    has_low_throttle: bool
    vertical_movement: bool
    horizontal_movement: bool
    rotational_movement: bool
    close_to_ground_or_skipped_check: bool
    at_rest: bool


class MulticopterLandDetector:
    """Clocked by the caller: ``update(now_us, inputs)`` at the local-position rate (PX4: on every
    ``vehicle_local_position``, at least every 50 ms). Publish the result when it changes, or at 1 Hz."""

    __slots__ = (
        "_alt_gnd",
        "_freefall",
        "_ground_contact",
        "_ground_effect",
        "_hover_estimate_valid",
        "_in_descend",
        "_landed",
        "_manual_thrust_min",
        "_maybe_landed",
        "_min_thrust_fallback",
        "_rot_max",
        "_stage_time_us",
        "_stage_us",
        "_thr_hover",
        "_thr_min",
        "_use_hte",
        "_xy_vel_max",
        "_z_vel_max",
        "state",
    )

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._freefall = Hysteresis(False)
        self._ground_contact = Hysteresis(True)
        self._maybe_landed = Hysteresis(True)
        self._landed = Hysteresis(True)
        self._ground_effect = Hysteresis(False)
        self._min_thrust_fallback = Hysteresis(False)
        self._freefall.set_hysteresis_time_from(False, FREEFALL_TRIGGER_TIME_US)
        self._min_thrust_fallback.set_hysteresis_time_from(False, MINIMUM_THRUST_FALLBACK_US)
        self._hover_estimate_valid = False
        self._in_descend = False
        self._stage_time_us = -1
        self.state = LandDetectorState(False, True, True, True, False, False, False, False, False, False, True, True)
        self.set_params(params or {})

    def resume_in_air(self) -> None:
        """Start from flying, not from the landed power-on state (a commander restarted in the air)."""
        for h in (self._ground_contact, self._maybe_landed, self._landed):
            h.force(False)
        self.state = self.state._replace(ground_contact=False, maybe_landed=False, landed=False, at_rest=False)

    def set_params(self, params: Mapping[str, object]) -> None:
        p = LandDetectorParams.from_params(params)
        # PX4 rewrites LNDMC_Z_VEL_MAX when it exceeds the slowest landing speed / 1.2.
        ceiling = min(p.mpc_land_crwl, p.mpc_land_speed) / 1.2
        self._z_vel_max = min(p.lndmc_z_vel_max, ceiling)
        self._xy_vel_max = p.lndmc_xy_vel_max
        self._rot_max = math.radians(p.lndmc_rot_max)
        self._alt_gnd = p.lndmc_alt_gnd
        self._thr_min = p.mpc_thr_min
        self._thr_hover = p.mpc_thr_hover
        # Manual-thrust modes idle at MPC_MANTHR_MIN; climb-rate modes at MPC_THR_MIN.
        self._manual_thrust_min = p.mpc_manthr_min + 0.01
        self._use_hte = bool(p.mpc_use_hte)
        self._stage_us = round(p.lndmc_trig_time * 1e6 / 3.0)
        self._stage_time_us = -1

    @property
    def vertical_speed_threshold(self) -> float:
        """LNDMC_Z_VEL_MAX after PX4's cap at min(MPC_LAND_CRWL, MPC_LAND_SPEED) / 1.2 [m/s]."""
        return self._z_vel_max

    def _set_stage_time(self, factor: int) -> None:
        stage_us = self._stage_us * factor
        if stage_us != self._stage_time_us:
            self._stage_time_us = stage_us
            for h in (self._ground_contact, self._maybe_landed, self._landed):
                h.set_hysteresis_time_from(False, stage_us)

    def update(self, now_us: int, inp: LandDetectorInputs) -> LandDetectorState:
        armed = inp.armed
        # A range finder that is fitted but out of range makes every stage three times slower.
        self._set_stage_time(3 if inp.dist_bottom_observable and not inp.dist_bottom_valid else 1)

        ax, ay, az = inp.acceleration
        freefall = self._freefall.set_state_and_update(
            math.sqrt(ax * ax + ay * ay + az * az) < FREEFALL_SPECIFIC_FORCE, now_us
        )

        lpos_available = now_us - inp.local_position_timestamp_us < POSITION_TIMEOUT_US
        was_landed = self._landed.state
        widen = LANDED_WIDENING if was_landed else 1.0
        vz_limit = self._z_vel_max * widen
        still_z = lpos_available and (
            (inp.v_z_valid and abs(inp.vz) < vz_limit) or (inp.z_valid and abs(inp.z_deriv) < vz_limit)
        )
        vertical_movement = not still_z
        horizontal_movement = lpos_available and inp.v_xy_valid and math.hypot(inp.vx, inp.vy) > self._xy_vel_max
        alt_gnd = self._alt_gnd
        below_ground_effect = lpos_available and inp.dist_bottom_valid and alt_gnd > 0.0 and inp.dist_bottom < alt_gnd

        thr_min = self._thr_min
        hover = self._thr_hover
        estimate_fresh = False
        if self._use_hte and math.isfinite(inp.hover_thrust):
            hover = inp.hover_thrust
            estimate_fresh = now_us - inp.hover_thrust_timestamp_us < HOVER_ESTIMATE_TIMEOUT_US
        # Keep using a valid estimate through a descent even if it stops updating.
        if not self._in_descend or estimate_fresh:
            self._hover_estimate_valid = estimate_fresh
        low_fraction = 0.6 if self._hover_estimate_valid else 0.3
        has_low_throttle = inp.throttle <= thr_min + (hover - thr_min) * low_fraction

        contact = has_low_throttle
        if inp.climb_rate_control:
            vz_sp = inp.velocity_setpoint_z
            self._in_descend = math.isfinite(vz_sp) and vz_sp >= 1.1 * self._z_vel_max
            # Until maybe-landed, ground contact needs a commanded descent.
            if not self._maybe_landed.state and not was_landed:
                contact = contact and self._in_descend
        else:
            self._in_descend = False
        close_to_ground = inp.dist_bottom_valid and inp.dist_bottom < DIST_FROM_GROUND_THRESHOLD
        close_or_skipped = close_to_ground or not inp.dist_bottom_observable or not inp.dist_bottom_valid
        ground_contact = self._ground_contact.set_state_and_update(
            not armed or (close_or_skipped and contact and not horizontal_movement and not vertical_movement), now_us
        )

        min_thrust = thr_min + (hover - thr_min) * 0.1 if inp.climb_rate_control else self._manual_thrust_min
        minimum_thrust_now = inp.throttle <= min_thrust
        fallback = self._min_thrust_fallback.set_state_and_update(minimum_thrust_now, now_us)
        wx, wy, _ = inp.angular_velocity
        rotational_movement = math.hypot(wx, wy) > self._rot_max * widen
        vertical_estimate = lpos_available and inp.v_z_valid
        maybe_landed = self._maybe_landed.set_state_and_update(
            not armed
            or (
                minimum_thrust_now
                and not freefall
                and not rotational_movement
                and ((vertical_estimate and ground_contact) or (not vertical_estimate and fallback))
            ),
            now_us,
        )
        landed = self._landed.set_state_and_update(not armed or maybe_landed, now_us)

        in_ground_effect = self._ground_effect.set_state_and_update(
            (self._in_descend and not horizontal_movement)
            or (below_ground_effect and inp.takeoff_state == TakeoffState.FLIGHT)
            or inp.takeoff_state == TakeoffState.RAMPUP,
            now_us,
        )

        self.state = LandDetectorState(
            freefall=freefall,
            ground_contact=ground_contact,
            maybe_landed=maybe_landed,
            landed=landed,
            in_ground_effect=in_ground_effect,
            in_descend=self._in_descend,
            has_low_throttle=has_low_throttle,
            vertical_movement=vertical_movement,
            horizontal_movement=horizontal_movement,
            rotational_movement=rotational_movement,
            close_to_ground_or_skipped_check=close_or_skipped,
            at_rest=landed and not (vertical_movement or horizontal_movement or rotational_movement),
        )
        return self.state
