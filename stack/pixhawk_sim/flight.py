"""The simulated Pixhawk's own control chain: PX4's loops, run by the Pixhawk on its own sensors.

Each IMU sample goes through PX4's gyro pipeline (``AngularVelocityFilter``) into the rate controller
(``RateControl`` with the yaw-torque low-pass, as ``mc_rate_control`` runs it), the control allocator and the
motor output stage (``ControlAllocator`` and ``MotorOutput``, as ``control_allocator`` runs them), whose
``actuator_outputs_sim`` view drives the simulator's motors. What feeds the rate controller depends on the mode:

* Offboard: the companion's body rates, or its attitude through ``AttitudeControl``, with its thrust;
* Hold (AUTO.LOITER) and Land (AUTO.LAND): the stack's ``FlightModeManager`` (PX4's navigator and flight
  tasks: Hold brakes to its stopping point and holds it, Land holds the landing point and descends at
  MPC_Z_V_AUTO_DN slowing to MPC_LAND_SPEED between MPC_LAND_ALT1 and MPC_LAND_ALT2 above home) into
  ``PositionControl`` at the local position's rate (50 Hz, as the stack's position estimator and PX4's EKF2
  run), then ``AttitudeControl``;
* on the ground in Hold or Land: motors at idle (PX4's takeoff state machine never leaves the ground unless
  asked to climb); disarmed or terminated: motors stopped.

The attitude and position the loops use are the simulator's truth (the Pixhawk's estimator is not simulated).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

from stack.attctl.attitude_control import AttitudeControl
from stack.attctl.rate_control import RateControl, YawTorqueLowPass, saturation_from_allocator
from stack.commander.home import HomePosition
from stack.estimator import position_kf
from stack.estimator.acceleration import VelocityDerivative
from stack.estimator.angular_velocity import AngularVelocityFilter, GyroFilterParams
from stack.mathlib import quaternion as quat
from stack.mathlib.quaternion import Quat
from stack.mathlib.vector import Vec3
from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.mixer.allocation import ControlAllocator
from stack.mixer.output import MotorOutput
from stack.pixhawk_sim.offboard import OffboardSetpoint
from stack.posctl import flight_task
from stack.posctl.flight_mode_manager import FlightModeManager, NavigatorInputs
from stack.posctl.position_control import PositionControl, PositionControlParams, failsafe_setpoint

NAN3: Vec3 = (math.nan, math.nan, math.nan)
ZERO3: Vec3 = (0.0, 0.0, 0.0)


class VehicleState(NamedTuple):
    """The Pixhawk's estimate of the vehicle (here the simulator's truth), NED about the origin, and its home."""

    time_us: int
    position: Vec3
    velocity: Vec3
    q: Quat
    home: HomePosition


class ControlOutput(NamedTuple):
    motors: tuple[float, ...]
    """The simulator's motor commands in [0, 1] (``actuator_outputs_sim``)."""
    pwm: tuple[float, ...]
    """PWM per motor [µs] (``actuator_outputs``, SERVO_OUTPUT_RAW)."""
    rates_sp: Vec3
    """Body-rate setpoint flown [rad/s] (NaN axis: hold)."""
    q_sp: Quat
    """Attitude setpoint flown (NaN when flying rates)."""
    thrust_body: Vec3
    """Normalised body thrust setpoint."""
    velocity_sp_z: float
    """Vertical velocity setpoint of position control [m/s down], NaN outside it (for the land detector)."""


_NAN_Q: Quat = (math.nan, math.nan, math.nan, math.nan)


class FlightControl:
    """PX4's rate, attitude and position loops with the allocator, for one vehicle (see the module docstring)."""

    def __init__(self, params: Mapping[str, object], imu_period_us: int) -> None:
        self.rates = AngularVelocityFilter(GyroFilterParams.from_params(params), sample_rate_hz=1e6 / imu_period_us)
        self.rate_control = RateControl(params)
        self.yaw_filter = YawTorqueLowPass(float(params["MC_YAW_TQ_CUTOFF"]))
        self.attitude_control = AttitudeControl(params)
        self.navigator = FlightModeManager(params)
        self.position_control = PositionControl(PositionControlParams.from_params(params))
        self.velocity_derivative = VelocityDerivative(float(params["MPC_VELD_LP"]))
        self.allocator = ControlAllocator.from_params(params)
        self.output = MotorOutput(self.allocator.num_motors, params)
        self._dt = imu_period_us * 1e-6
        self._position_every = position_kf.PERIOD_US // imu_period_us
        self._land_speed = float(params["MPC_LAND_SPEED"])
        self._mode: Px4Mode | None = None
        self._position_tick = 0
        self._position_sp: tuple[Quat, Vec3, float, float] = (_NAN_Q, ZERO3, math.nan, math.nan)
        """The last position-control output: attitude, body thrust, yaw feed-forward, vertical velocity."""
        self.last = ControlOutput(
            (0.0,) * self.allocator.num_motors, (0.0,) * self.allocator.num_motors, NAN3, _NAN_Q, ZERO3, math.nan
        )

    @property
    def body_rates(self) -> Vec3:
        """Filtered body rates [rad/s] (PX4 ``vehicle_angular_velocity``)."""
        return self.rates.xyz

    def update(
        self,
        gyro_time_us: int,
        gyro: Vec3,
        state: VehicleState,
        mode: Px4Mode,
        armed: bool,
        landed: bool,
        maybe_landed: bool,
        setpoint: OffboardSetpoint | None,
    ) -> ControlOutput:
        """One rate-loop cycle on a new gyro sample; returns the motor commands and what was flown."""
        rates, rates_derivative = self.rates.update(gyro_time_us, gyro)
        if mode is not self._mode:
            self._enter(mode, state)
        q_sp, thrust, velocity_sp_z = _NAN_Q, ZERO3, math.nan
        flying = armed and mode is not Px4Mode.TERMINATION
        if not flying:
            rates_sp = NAN3
        elif mode is Px4Mode.OFFBOARD and setpoint is not None:
            thrust = setpoint.thrust_body
            if setpoint.is_attitude:
                q_sp = setpoint.q
                self.attitude_control.set_attitude_setpoint(q_sp, setpoint.rates[2])
                rates_sp = self.attitude_control.update(state.q)
            else:
                rates_sp = setpoint.rates
        elif mode in (Px4Mode.AUTO_LOITER, Px4Mode.AUTO_LAND) and not landed:
            q_sp, thrust, yaw_rate, velocity_sp_z = self._position(state, mode)
            self.attitude_control.set_attitude_setpoint(q_sp, yaw_rate)
            rates_sp = self.attitude_control.update(state.q)
        else:
            rates_sp = ZERO3
        if not flying:
            self.rate_control.reset_integral()
            self.yaw_filter.reset()
        torque = self.rate_control.update(rates, rates_sp, rates_derivative, self._dt, landed or maybe_landed)
        torque = (torque[0], torque[1], self.yaw_filter.update(torque[2], self._dt))
        result = self.allocator.allocate(torque, thrust)
        saturation = saturation_from_allocator(result.torque_achieved, result.unallocated_torque)
        self.rate_control.set_saturation_status(*saturation)
        out = self.output.update(result.motors, flying, self._dt)
        self.last = ControlOutput(out.sim, out.pwm, rates_sp, q_sp, thrust, velocity_sp_z)
        return self.last

    def _enter(self, mode: Px4Mode, state: VehicleState) -> None:
        """A new mode: position control starts afresh, and so does the navigator (a disarmed update resets its
        task, so a Hold entered again brakes to its new stopping point)."""
        self._mode = mode
        self._position_tick = 0
        self.position_control.reset_integral()
        self.velocity_derivative.reset()
        self.navigator.update(self._navigator_inputs(state, mode, armed=False), 0.0)

    @staticmethod
    def _navigator_inputs(state: VehicleState, mode: Px4Mode, armed: bool) -> NavigatorInputs:
        task_state = flight_task.VehicleState(
            state.time_us, state.position, state.velocity, quat.yaw(state.q), False, True
        )
        return NavigatorInputs(task_state, px4_modes.to_nav_state(mode), armed, state.home, None, None)

    def _position(self, state: VehicleState, mode: Px4Mode) -> tuple[Quat, Vec3, float, float]:
        """Hold or Land at PX4's local-position rate; the output is held in between."""
        self._position_tick -= 1
        if self._position_tick > 0:
            return self._position_sp
        self._position_tick = self._position_every
        dt = position_kf.PERIOD_US * 1e-6
        command = self.navigator.update(self._navigator_inputs(state, mode, armed=True), dt)
        velocity_dot = self.velocity_derivative.update(state.time_us, state.velocity)
        control = self.position_control
        control.set_state(state.position, state.velocity, velocity_dot or ZERO3, quat.yaw(state.q))
        if command is not None:
            control.set_setpoint(
                command.position, command.velocity, command.acceleration, command.yaw, command.yawspeed
            )
        if command is None or not control.update(dt):
            fallback = failsafe_setpoint(state.velocity, self._land_speed)
            control.set_setpoint(fallback.position, fallback.velocity, fallback.acceleration, math.nan, math.nan)
            control.update(dt)
        q_d, thrust_body, yaw_rate = control.attitude_setpoint()
        self._position_sp = (q_d, thrust_body, yaw_rate, control.local_position_setpoint().velocity[2])
        return self._position_sp
