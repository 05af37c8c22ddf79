"""The simulated Pixhawk without its MAVLink side: the plant, its sensors and the autopilot flying it.

:class:`SimulatedPixhawk` steps the stack's simulator (physics and sensors, PX4 SIH's IMU rate) and, on each
IMU sample, the Pixhawk's commander, land detector (at PX4's 50 Hz) and control chain, whose motor commands
drive the next step. Its clock is the autopilot's boot time: the simulated time plus any time the caller
skipped because the wall clock ran ahead (:meth:`skip`), so sample times stay on the wall clock they are
paced to. It is free of I/O; the MAVLink endpoint reads its state and hands it commands and setpoints.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

from pymavlink.dialects.v20 import common as mavlink

from stack.airframe.model import VehicleModel
from stack.commander import land_detector
from stack.commander.home import HomePosition
from stack.commander.land_detector import LandDetectorInputs, LandDetectorState, MulticopterLandDetector
from stack.mathlib import quaternion as quat
from stack.mavlink.px4_modes import Px4Mode
from stack.pixhawk_sim.commander import Condition, Px4Commander, Verdict
from stack.pixhawk_sim.flight import ControlOutput, FlightControl, VehicleState
from stack.pixhawk_sim.offboard import OffboardSetpoint, decode_attitude_target
from stack.sim import battery
from stack.sim.battery import BatteryModel, BatteryState
from stack.sim.sensors import BaroSample, GpsSample, ImuSample, MagSample
from stack.sim.simulator import GroundTruth, Simulator


class Sample(NamedTuple):
    """A sensor sample with the autopilot's boot time [µs] of its measurement, and its sequence number."""

    boot_us: int
    value: ImuSample | MagSample | BaroSample | GpsSample
    sequence: int


class SimulatedPixhawk:
    """See the module docstring."""

    def __init__(self, model: VehicleModel, params: Mapping[str, object], seed: int = 0) -> None:
        self.params = dict(params)
        self.sim = Simulator(
            model,
            seed=seed,
            home=(float(params["SIH_LOC_LAT0"]), float(params["SIH_LOC_LON0"]), float(params["SIH_LOC_H0"])),
        )
        period_us = self.sim.imu_period_us
        self._land_detector_every = land_detector.PERIOD_US // period_us
        self._battery_every = battery.PERIOD_US // period_us
        self.commander = Px4Commander(params)
        self.control = FlightControl(params, period_us)
        self.land_detector = MulticopterLandDetector(params)
        self.battery = BatteryModel(params)
        self.battery_state: BatteryState = self.battery.update(0.0, False)
        self.setpoint: OffboardSetpoint | None = None
        self.samples: dict[type, Sample] = {}
        self.skipped_us = 0
        self.steps = 0
        self.truth: GroundTruth = self.sim.truth()
        self.home = self._home_here()
        self._motors: tuple[float, ...] = (0.0,) * model.rotor_count
        self._sequence = 0

    @property
    def time_us(self) -> int:
        """The autopilot's boot time [µs]."""
        return self.sim.time_us + self.skipped_us

    @property
    def period_us(self) -> int:
        return self.sim.imu_period_us

    @property
    def landed(self) -> LandDetectorState:
        return self.land_detector.state

    @property
    def output(self) -> ControlOutput:
        return self.control.last

    def skip(self, duration_us: int) -> None:
        """The wall clock moved on by ``duration_us`` without the simulation (the caller fell behind)."""
        self.skipped_us += duration_us

    def step(self) -> None:
        """Advance one IMU period and run the autopilot on the new samples."""
        for value in self.sim.advance(self._motors):
            self._sequence += 1
            self.samples[type(value)] = Sample(value.time_us + self.skipped_us, value, self._sequence)
        self.truth = truth = self.sim.truth()
        now = self.time_us
        commander = self.commander
        if self.steps % self._land_detector_every == 0:
            self._detect_landing(now, truth)
            commander.update(now, self.condition())
        land = self.land_detector.state
        imu = self.samples[ImuSample]
        state = VehicleState(now, truth.position, truth.velocity, truth.q, self.home)
        out = self.control.update(
            imu.boot_us,
            imu.value.gyro,
            state,
            mode=commander.mode,
            armed=commander.armed,
            landed=land.landed,
            maybe_landed=land.maybe_landed,
            setpoint=self.setpoint,
        )
        self._motors = out.motors
        if self.steps % self._battery_every == 0:
            self.battery_state = self.battery.update(battery.PERIOD_US * 1e-6, commander.armed)
        self.steps += 1

    def _detect_landing(self, now: int, truth: GroundTruth) -> None:
        imu = self.samples[ImuSample].value
        self.land_detector.update(now, land_detector_inputs(now, truth, imu, self.commander, self.control))

    def condition(self) -> Condition:
        return condition(self.land_detector.state, self.truth)

    # ------------------------------------------------------------------ commands and setpoints

    def arm_disarm(self, arm: bool, force: bool) -> Verdict:
        was_armed = self.commander.armed
        verdict = self.commander.arm_disarm(arm, force, self.time_us, self.condition())
        if self.commander.armed and not was_armed:
            self.home = self._home_here()
        return verdict

    def _home_here(self) -> HomePosition:
        return home_here(self.truth)

    def set_mode(self, mode: Px4Mode | None) -> Verdict:
        return self.commander.set_mode(mode, self.time_us)

    def attitude_target(self, msg: mavlink.MAVLink_set_attitude_target_message) -> None:
        """A SET_ATTITUDE_TARGET for this vehicle: proof of life, and the setpoint when it carries one."""
        self.commander.offboard_setpoint(self.time_us)
        setpoint = decode_attitude_target(msg, self.setpoint)
        if setpoint is not None:
            self.setpoint = setpoint

    @property
    def flying_attitude(self) -> bool:
        """Whether the attitude is controlled in Offboard (attitude setpoints rather than body rates)."""
        return self.setpoint is not None and self.setpoint.is_attitude


def land_detector_inputs(
    now_us: int, truth: GroundTruth, imu: ImuSample, commander: Px4Commander, control: FlightControl
) -> LandDetectorInputs:
    """The land detector's inputs: the truth for the estimate, the last control output for the thrust and the
    vertical velocity setpoint (PX4 ``MulticopterLandDetector``), climb rate controlled in Hold and Land."""
    out = control.last
    vx, vy, vz = truth.velocity
    return LandDetectorInputs(
        armed=commander.armed,
        local_position_timestamp_us=now_us,
        z_valid=True,
        v_xy_valid=True,
        v_z_valid=True,
        vx=vx,
        vy=vy,
        vz=vz,
        z_deriv=vz,
        angular_velocity=control.body_rates,
        acceleration=imu.accel,
        throttle=-out.thrust_body[2],
        climb_rate_control=commander.mode in (Px4Mode.AUTO_LOITER, Px4Mode.AUTO_LAND),
        velocity_setpoint_z=out.velocity_sp_z,
    )


def condition(land: LandDetectorState, truth: GroundTruth) -> Condition:
    """What the commander needs to know about the vehicle: landed, and its tilt."""
    roll, pitch, _ = quat.to_euler(truth.q)
    return Condition(land.landed, land.maybe_landed, roll, pitch)


def home_here(truth: GroundTruth) -> HomePosition:
    """Home where the vehicle is (PX4 sets it on arming)."""
    x, y, z = truth.position
    return HomePosition(x, y, z, quat.yaw(truth.q), truth.lat, truth.lon, truth.alt)
