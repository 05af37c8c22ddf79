"""PX4's fixed-wing land detector: landed when slow and still for LNDFW_TRIG_TIME.

Follows ``src/modules/land_detector/FixedwingLandDetector.cpp`` (PX4 main), run at the land detector's 50 Hz
(the filter constants are per update, as there): armed, with a local position younger than 1 s, it low-pass
filters

* the horizontal ground speed (0.97/0.03, only while ``v_xy_valid``) and the vertical speed (0.99/0.01);
* the true airspeed (0.95/0.05; zero while there is none: NaN, or ``airspeed_validated`` older than 1 s);
* the horizontal specific force, body x and y of the accelerometer (a leaking 0.8/0.18 filter, so that a
  bias does not build up but a short impulse counts);
* the angular rate's magnitude (0.95/0.05),

and asks for "landed" when each is below its limit: LNDFW_AIRSPD_MAX, LNDFW_VEL_XY_MAX (× 0.7 without an
airspeed), LNDFW_VEL_Z_MAX, LNDFW_XYACC_MAX and — only when neither the ground speed nor an airspeed can be
used — LNDFW_ROT_MAX. The request must hold LNDFW_TRIG_TIME to land; taking off is immediate. Disarmed, or
without a local position, the vehicle is landed. A plane has no freefall, ground contact, maybe-landed or
ground-effect stage: those stay false, as PX4's base class leaves them. PX4's hold while a catapult launch is
awaited does not apply (the stack's planes take off from a runway). ``at_rest`` is landed with no motion
for 1 s: the angular rate below 3 °/s (PX4 ``GYRO_NORM_MAX``), the engine at idle and the specific force
within 0.5 m/s² of its value at rest. PX4's ``LandDetector::UpdateVehicleAtRest`` reads motion from the IMU's
vibration metrics, which a running engine raises; a simulated engine does not vibrate, so the throttle and a
step of the specific force take their place. It matters: the position estimate fuses zero velocity while at
rest, and "landed" alone lasts into the takeoff roll (until the filtered airspeed passes LNDFW_AIRSPD_MAX),
long enough to pin the estimate metres behind a plane accelerating down the runway and have its GPS rejected.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from stack.commander.hysteresis import Hysteresis
from stack.commander.land_detector import LandDetectorState, throttle_in_mode
from stack.mathlib.vector import ZERO3, Vec3
from stack.msg.estimation import VehicleImuStatus, VehicleLocalPosition
from stack.msg.fixedwing import AIRSPEED_TIMEOUT_US, AirspeedValidated
from stack.msg.setpoints import VehicleThrustSetpoint
from stack.params.binding import ParamSet
from stack.params.param import Param


class FwLandDetectorParams(ParamSet):
    """The fixed-wing detector's thresholds (the catalogue's LNDFW_*)."""

    lndfw_trig_time: float
    lndfw_vel_xy_max: float
    lndfw_vel_z_max: float
    lndfw_airspd_max: float
    lndfw_xyacc_max: float
    lndfw_rot_max: float


PARAMS: tuple[Param, ...] = FwLandDetectorParams.PARAMS

POSITION_TIMEOUT_US = 1_000_000
NO_AIRSPEED_XY_FACTOR = 0.7
"""The ground-speed limit is tightened by this factor when there is no airspeed."""
AT_REST_RATE = math.radians(3.0)
"""Angular rate [rad/s] above which the vehicle moves (PX4 ``GYRO_NORM_MAX``)."""
AT_REST_TIME_US = 1_000_000
AT_REST_THROTTLE_MAX = 0.05
"""Throttle [0, 1] above which the engine runs, and so the vehicle is not at rest."""
AT_REST_ACCEL_STEP = 0.5
"""Specific-force change [m/s²] from its value at rest that counts as motion (a throttle-up on the runway)."""
AT_REST_ACCEL_KEEP = 0.98
"""Per-update weight of the specific force's reference at rest: a 1 s time constant at 50 Hz, so a vehicle
parked on a slope or after a landing settles to rest."""


@dataclass(slots=True)
class FixedwingLandDetectorInputs:
    """The latest values of the detector's inputs; the module glue copies them from topics.

    ``true_airspeed`` is ``airspeed_validated.true_airspeed_m_s`` (NaN: none) and ``airspeed_timestamp_us``
    its time; ``acceleration`` the specific force in the body frame [m/s²], ``angular_velocity`` the body
    rates [rad/s], ``throttle`` the forward thrust setpoint [0, 1].
    """

    armed: bool = False
    local_position_timestamp_us: int = 0
    v_xy_valid: bool = False
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    airspeed_timestamp_us: int = 0
    true_airspeed: float = math.nan
    acceleration: Vec3 = (0.0, 0.0, -9.80665)
    angular_velocity: Vec3 = ZERO3
    throttle: float = 0.0


def fixedwing_inputs(
    armed: bool,
    nav_state: int,
    lpos: VehicleLocalPosition | None,
    airspeed: AirspeedValidated | None,
    imu: VehicleImuStatus | None,
    thrust: VehicleThrustSetpoint | None,
) -> FixedwingLandDetectorInputs:
    """The detector's inputs from the latest messages (None: none received), as ``FixedwingLandDetector.cpp``
    reads its topics."""
    inp = FixedwingLandDetectorInputs(armed=armed)
    if lpos is not None:
        inp.local_position_timestamp_us = lpos.timestamp
        inp.v_xy_valid, inp.vx, inp.vy, inp.vz = lpos.v_xy_valid, lpos.vx, lpos.vy, lpos.vz
    if airspeed is not None:
        inp.airspeed_timestamp_us, inp.true_airspeed = airspeed.timestamp, airspeed.true_airspeed_m_s
    if imu is not None:
        inp.angular_velocity = imu.mean_gyro
        inp.acceleration = imu.mean_accel
    if thrust is not None:
        inp.throttle = thrust.xyz[0]
    inp.throttle = throttle_in_mode(inp.throttle, nav_state)
    return inp


def _landed_state(landed: bool, at_rest: bool) -> LandDetectorState:
    return LandDetectorState(
        freefall=False,
        ground_contact=False,
        maybe_landed=False,
        landed=landed,
        in_ground_effect=False,
        in_descend=False,
        has_low_throttle=False,
        vertical_movement=False,
        horizontal_movement=False,
        rotational_movement=False,
        close_to_ground_or_skipped_check=False,
        at_rest=landed and at_rest,
    )


class FixedwingLandDetector:
    """Clocked by the caller: ``update(now_us, inputs)`` every 20 ms (PX4's land detector rate)."""

    __slots__ = (
        "_accel_rest",
        "_accel_xy_filtered",
        "_airspeed_filtered",
        "_airspeed_max",
        "_landed",
        "_rot_max",
        "_rotation_filtered",
        "_still",
        "_vel_xy_filtered",
        "_vel_xy_max",
        "_vel_z_filtered",
        "_vel_z_max",
        "_xyacc_max",
        "state",
    )

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self._landed = Hysteresis(True)
        self._still = Hysteresis(True)
        self._still.set_hysteresis_time_from(False, AT_REST_TIME_US)
        self._vel_xy_filtered = 0.0
        self._vel_z_filtered = 0.0
        self._airspeed_filtered = 0.0
        self._accel_xy_filtered = 0.0
        self._rotation_filtered = 0.0
        self._accel_rest: Vec3 | None = None
        self.state = _landed_state(True, True)
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = FwLandDetectorParams.from_params(params)
        self._landed.set_hysteresis_time_from(False, round(p.lndfw_trig_time * 1e6))
        self._vel_xy_max = p.lndfw_vel_xy_max
        self._vel_z_max = p.lndfw_vel_z_max
        self._airspeed_max = p.lndfw_airspd_max
        self._xyacc_max = p.lndfw_xyacc_max
        self._rot_max = math.radians(p.lndfw_rot_max)

    def resume_in_air(self) -> None:
        """Start from flying, not from the landed power-on state (a commander restarted in the air)."""
        self._landed.force(False)
        self.state = _landed_state(False, False)

    def update(self, now_us: int, inp: FixedwingLandDetectorInputs) -> LandDetectorState:
        landed = self._landed.set_state_and_update(self._landed_now(now_us, inp), now_us)
        wx, wy, wz = inp.angular_velocity
        rate = math.sqrt(wx * wx + wy * wy + wz * wz)
        engine_running = not inp.throttle <= AT_REST_THROTTLE_MAX  # NaN: running
        moving = self._accel_stepped(inp.acceleration) or rate > AT_REST_RATE or engine_running
        still = self._still.set_state_and_update(not moving, now_us)
        self.state = _landed_state(landed, still)
        return self.state

    def _accel_stepped(self, accel: Vec3) -> bool:
        """Whether the specific force left its reference at rest by more than AT_REST_ACCEL_STEP; the reference
        follows it slowly. A non-finite sample is motion (nothing is known) and leaves the reference alone."""
        if not all(math.isfinite(a) for a in accel):
            return True
        rest = self._accel_rest if self._accel_rest is not None else accel
        stepped = math.dist(accel, rest) > AT_REST_ACCEL_STEP
        keep = AT_REST_ACCEL_KEEP
        self._accel_rest = (
            keep * rest[0] + (1 - keep) * accel[0],
            keep * rest[1] + (1 - keep) * accel[1],
            keep * rest[2] + (1 - keep) * accel[2],
        )
        return stepped

    def _landed_now(self, now_us: int, inp: FixedwingLandDetectorInputs) -> bool:
        """PX4 ``FixedwingLandDetector::_get_landed_state``: whether the conditions for "landed" hold now."""
        if not inp.armed or now_us - inp.local_position_timestamp_us >= POSITION_TIMEOUT_US:
            return True
        if inp.v_xy_valid:
            self._vel_xy_filtered = _filtered(self._vel_xy_filtered, math.hypot(inp.vx, inp.vy), 0.97, 0.03)
        self._vel_z_filtered = _filtered(self._vel_z_filtered, abs(inp.vz), 0.99, 0.01)
        airspeed = inp.true_airspeed
        airspeed_valid = math.isfinite(airspeed) and now_us - inp.airspeed_timestamp_us <= AIRSPEED_TIMEOUT_US
        if airspeed_valid:
            self._airspeed_filtered = _filtered(self._airspeed_filtered, airspeed, 0.95, 0.05)
        else:
            self._airspeed_filtered = 0.0
        ax, ay, _ = inp.acceleration
        self._accel_xy_filtered = _filtered(self._accel_xy_filtered, math.hypot(ax, ay), 0.8, 0.18)
        wx, wy, wz = inp.angular_velocity
        self._rotation_filtered = _filtered(self._rotation_filtered, math.sqrt(wx * wx + wy * wy + wz * wz), 0.95, 0.05)

        vel_xy_max = self._vel_xy_max if airspeed_valid else NO_AIRSPEED_XY_FACTOR * self._vel_xy_max
        rotation_max = self._rot_max if not (inp.v_xy_valid or airspeed_valid) else math.inf
        return (
            self._airspeed_filtered < self._airspeed_max
            and self._vel_xy_filtered < vel_xy_max
            and self._vel_z_filtered < self._vel_z_max
            and self._accel_xy_filtered < self._xyacc_max
            and self._rotation_filtered < rotation_max
        )


def _filtered(previous: float, sample: float, keep: float, gain: float) -> float:
    """One step of PX4's ``keep·previous + gain·sample``; a non-finite sample is ignored."""
    value = keep * previous + gain * sample
    return value if math.isfinite(value) else previous
