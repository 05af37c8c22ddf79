"""The attitude-flight chain in one process: simulator, estimator, attitude and rate loops, allocator.

It wires the same algorithm classes the modules use, with the same one-step delays the lockstep
gives the multi-process stack (a module sees other modules' outputs of the previous step), so a
controller can be tuned or tested in seconds and the numbers carry over to the full stack.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from stack.attctl.attitude_control import AttitudeControl
from stack.attctl.input_shaping import AttitudeInputShaper, combine_with_feedforward
from stack.attctl.rate_control import RateControl, YawTorqueLowPass
from stack.estimator.acceleration import VelocityDerivative
from stack.estimator.angular_velocity import AngularVelocityFilter
from stack.estimator.attitude_q import AttitudeEstimatorQ
from stack.mathlib.quaternion import Quat
from stack.mathlib.vector import Vec3
from stack.mixer.allocation import ControlAllocator
from stack.mixer.output import MotorOutput
from stack.sim.sensors import GpsSample, ImuSample, MagSample
from stack.sim.simulator import GroundTruth, Simulator
from stack.sim.vehicle import load_vehicle

FLT_EPSILON = 1.1920929e-07


@dataclass
class StepRecord:
    time_us: int
    truth: GroundTruth
    estimate: Quat
    rate_setpoint: Vec3


class InProcessAttitudeFlight:
    """Fly attitude and thrust setpoints on a simulated vehicle, all in this process."""

    def __init__(self, vehicle: str = "sih_quad", params: Mapping[str, object] | None = None, seed: int = 1) -> None:
        model = load_vehicle(vehicle)
        values: dict[str, object] = {**model.airframe, **(params or {})}
        self.sim = Simulator(model, seed=seed)
        self.estimator = AttitudeEstimatorQ(
            **{
                k: values[k]
                for k in ("ATT_W_ACC", "ATT_W_MAG", "ATT_W_GYRO_BIAS", "ATT_BIAS_MAX", "ATT_MAG_DECL", "ATT_ACC_COMP")
                if k in values
            }
        )
        self.acceleration = VelocityDerivative(float(values.get("ATT_ACC_COMP_LP", 1.0)))
        self.rates = AngularVelocityFilter(
            **{k: values[k] for k in ("IMU_GYRO_CUTOFF", "IMU_DGYRO_CUTOFF") if k in values}
        )
        self.attitude = AttitudeControl(values)
        self.shaper = AttitudeInputShaper(values)
        self.shaping = bool(values.get("MC_INPUT_SHAPING", 0))
        self.rate = RateControl(values)
        self.yaw_filter = YawTorqueLowPass(float(values.get("MC_YAW_TQ_CUTOFF", 2.0)))
        self.allocator = ControlAllocator.from_params(values)
        self.output = MotorOutput(self.allocator.num_motors, values)
        self.dt = self.sim.imu_period_us * 1e-6
        self.q_sp: Quat = (1.0, 0.0, 0.0, 0.0)
        self.thrust = 0.0
        self.armed = False
        self._rates_sp_prev: Vec3 = (0.0, 0.0, 0.0)
        self._thrust_prev = 0.0
        self._sim_commands: tuple[float, ...] = (0.0,) * self.allocator.num_motors
        self._saturation = ((False,) * 3, (False,) * 3)
        self._shaper_engaged = False

    def step(self) -> StepRecord:
        """One lockstep step: physics with last step's outputs, then every loop once."""
        samples = self.sim.advance(self._sim_commands)
        imu = next(s for s in samples if isinstance(s, ImuSample))
        mag = next((s.field for s in samples if isinstance(s, MagSample)), None)
        for gps in (s for s in samples if isinstance(s, GpsSample)):
            self.acceleration.update(gps.time_us, gps.vel_ned)
        self.estimator.update(self.dt, imu.gyro, imu.accel, mag, self.acceleration.acceleration)
        xyz, xyz_dot = self.rates.update(imu.time_us, imu.gyro, self.estimator.gyro_bias)
        q = self.estimator.q
        # Rate loop: this step's rates, the attitude loop's setpoint of the previous step.
        self.rate.set_saturation_status(*self._saturation)
        torque = self.rate.update(xyz, self._rates_sp_prev, xyz_dot, self.dt, landed=not self.armed)
        torque = (torque[0], torque[1], self.yaw_filter.update(torque[2], self.dt))
        result = self.allocator.allocate(torque, (0.0, 0.0, -self._thrust_prev))
        self._sim_commands = self.output.update(result.motors, self.armed, self.dt).sim
        self._saturation = (
            tuple(u > FLT_EPSILON for u in result.unallocated_torque) if not result.torque_achieved else (False,) * 3,
            tuple(u < -FLT_EPSILON for u in result.unallocated_torque) if not result.torque_achieved else (False,) * 3,
        )
        # Attitude loop (its output is used by the rate loop next step).
        if self.shaping:
            if not self._shaper_engaged:
                self.shaper.reset(q)
                self._shaper_engaged = True
            shaped = self.shaper.input_quaternion(self.q_sp, q, self.dt)
            self.attitude.set_attitude_setpoint(shaped.q_target, math.nan)
            rates_sp = combine_with_feedforward(self.attitude.update(q), shaped, xyz)
        else:
            self.attitude.set_attitude_setpoint(self.q_sp, math.nan)
            rates_sp = self.attitude.update(q)
        self._rates_sp_prev = rates_sp
        self._thrust_prev = self.thrust
        return StepRecord(self.sim.time_us, self.sim.truth(), q, rates_sp)
