"""roll_pitch_yawrate_thrust_controller: RotorS' attitude controller and rotor allocation, run on every attitude
estimate, as RotorS' node runs on every odometry message and publishes rotor speeds
(``rotors_control/src/nodes/roll_pitch_yawrate_thrust_controller_node.cpp``, ethz-asl/rotors_simulator).

On the RotorS profiles it stands in for mc_att_control, mc_rate_control and control_allocator. What it follows
depends on ``vehicle_control_mode``:

- the RotorS mode (flag_control_rpyt_enabled): ``roll_pitch_yawrate_thrust_setpoint`` (rotors_joy_interface's,
  or any publisher's), each new one taken and held, as RotorS holds its last command;
- attitude control: an attitude setpoint made a RotorS command (:mod:`stack.attctl.rpyt_setpoints`): in
  Stabilized the sticks' (published on ``vehicle_attitude_setpoint`` as mc_att_control does), otherwise
  ``vehicle_attitude_setpoint`` (mc_pos_control, Offboard attitude); Rattitude's large deflections fly as Acro;
- body rates without attitude: Acro's sticks, or ``vehicle_rates_setpoint`` (Offboard body rates), through the
  same law with no attitude term (the stack's extension);
- otherwise (Termination) no new command.

A command that is not finite is refused and the last good one kept. ``actuator_motors`` and
``actuator_outputs_sim`` carry each motor's command u = ω/ω_max, RotorS' motor speed over its maximum: no PWM
idle, so the simulated rotor turns at the speed the law asked for. The motors stop (NaN on actuator_motors, 0 for
the simulator) while disarmed, in lockdown, killed or terminated, as control_allocator and PX4's output drivers
stop them, and the controller then forgets its command, so they stay stopped until a new one. The collective
thrust goes out normalised on ``vehicle_thrust_setpoint``, for the land detector.

The vehicle (inertia, rotors, motors) is read from its model file, as RotorS' node reads its
``rotors_gazebo/resource/<mav>.yaml``; the gains are the RPYT_* parameters.
"""

from __future__ import annotations

import math

from stack.airframe.model import load_vehicle
from stack.attctl import rate_control, rpyt_control, stabilized
from stack.attctl.rate_control import AcroStickMapping
from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.attctl.rpyt_control import RollPitchYawrateThrustControl
from stack.attctl.rpyt_setpoints import command_from_attitude, thrust_newtons
from stack.attctl.stabilized import rattitude_uses_rate_control
from stack.attctl.stick_attitude import StickAttitudeSetpoint
from stack.mathlib.quaternion import Quat
from stack.mathlib.vector import Vec3
from stack.msg.actuators import MOTOR_SLOTS, OUTPUT_SLOTS, ActuatorMotors, ActuatorOutputs, pad
from stack.msg.estimation import VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint
from stack.msg.system import VehicleControlMode
from stack.params import catalogue
from stack.params.binding import combine
from stack.runtime.module import Arg, Module, Trigger
from stack.runtime.priority import RATE_CTRL

_NO_MODE = VehicleControlMode()
_NO_RATES: Vec3 = (math.nan, math.nan, math.nan)


class RollPitchYawrateThrustController(Module):
    NAME = "roll_pitch_yawrate_thrust_controller"
    WORK_QUEUE = RATE_CTRL
    DESCRIPTION = "RotorS roll-pitch-yawrate-thrust controller: attitude law and rotor allocation → motor commands"
    TRIGGER = Trigger(ORB_ID.vehicle_attitude)
    DT_RANGE = (0.0002, 0.02)
    PARAMS = combine(rpyt_control.PARAMS, stabilized.PARAMS, rate_control.ACRO_PARAMS, catalogue.params("MC_YAW_P"))
    ARGS = (Arg("vehicle", "", "Vehicle model: a name in stack/airframe/vehicles or a path to a model file"),)
    PUBLISHES = (
        ORB_ID.actuator_motors,
        ORB_ID.actuator_outputs_sim,
        ORB_ID.vehicle_thrust_setpoint,
        ORB_ID.vehicle_attitude_setpoint,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        if not self.args["vehicle"]:
            raise ValueError("no vehicle model: set the module's args.vehicle (e.g. \"firefly\")")
        vehicle = load_vehicle(str(self.args["vehicle"]))
        for topic in (
            ORB_ID.vehicle_angular_velocity,
            ORB_ID.vehicle_control_mode,
            ORB_ID.actuator_armed,
            ORB_ID.roll_pitch_yawrate_thrust_setpoint,
            ORB_ID.vehicle_attitude_setpoint,
            ORB_ID.vehicle_rates_setpoint,
            ORB_ID.manual_control_setpoint,
            ORB_ID.vehicle_land_detected,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        values = self.params.values()
        self.control = RollPitchYawrateThrustControl(vehicle, values)
        self.sticks = StickAttitudeSetpoint(values)
        self.acro = AcroStickMapping(values)
        self._refused: object = None
        self.log.info("RotorS controller for %s: %d rotors", vehicle.name, vehicle.rotor_count)

    def on_params_changed(self, changed: set[str]) -> None:
        values = self.params.values()
        self.control.set_params(values)
        self.sticks.set_params(values)
        self.acro.set_params(values)

    def run(self, att: VehicleAttitude, dt: float) -> None:
        rates = self.latest(ORB_ID.vehicle_angular_velocity)
        body_rates = rates.xyz if rates is not None else _NO_RATES
        self._follow(att.q, self.latest(ORB_ID.vehicle_control_mode) or _NO_MODE, dt)
        armed = self.latest(ORB_ID.actuator_armed)
        n = self.control.num_rotors
        if armed is not None and armed.armed and not (armed.lockdown or armed.kill or armed.termination):
            motors = self.control.motors(att.q, body_rates)
            control, sim = pad(motors, MOTOR_SLOTS, math.nan), pad(motors, OUTPUT_SLOTS, 0.0)
        else:
            self.control.reset()
            control, sim = pad((), MOTOR_SLOTS, math.nan), pad((), OUTPUT_SLOTS, 0.0)
        t = att.timestamp_sample
        thrust = (0.0, 0.0, -self.control.thrust / self.control.max_thrust)
        self.publish(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(timestamp_sample=t, xyz=thrust))
        self.publish(ORB_ID.actuator_motors, ActuatorMotors(timestamp_sample=t, control=control))
        self.publish(ORB_ID.actuator_outputs_sim, ActuatorOutputs(noutputs=n, output=sim))

    def _follow(self, q: Quat, mode: VehicleControlMode, dt: float) -> None:
        """Give the controller this cycle's command for the control mode (see the module docstring)."""
        rotors_setpoint = self.update(ORB_ID.roll_pitch_yawrate_thrust_setpoint)
        sticks = self.latest(ORB_ID.manual_control_setpoint)
        land = self.latest(ORB_ID.vehicle_land_detected)
        stick_setpoint = self.sticks.update(q, mode, sticks, land is not None and land.landed, dt, self.now_us())
        attitude = mode.flag_control_attitude_enabled and not (
            mode.flag_control_rattitude_enabled
            and sticks is not None
            and rattitude_uses_rate_control(sticks.roll, sticks.pitch, float(self.params["MC_RATT_TH"]))
        )
        max_thrust = self.control.max_thrust
        if mode.flag_control_rpyt_enabled:
            if rotors_setpoint is not None:
                command = RollPitchYawrateThrust(
                    rotors_setpoint.roll, rotors_setpoint.pitch, rotors_setpoint.yaw_rate, rotors_setpoint.thrust
                )
                self._command(self.control.set_command(command), rotors_setpoint)
        elif attitude:
            setpoint = stick_setpoint
            if setpoint is not None:
                self.publish(ORB_ID.vehicle_attitude_setpoint, setpoint)
            else:
                setpoint = self.latest(ORB_ID.vehicle_attitude_setpoint)
            if setpoint is not None:
                command = command_from_attitude(
                    q, setpoint.q_d, setpoint.yaw_sp_move_rate, setpoint.thrust_body,
                    float(self.params["MC_YAW_P"]), max_thrust,
                )
                self._command(self.control.set_command(command), setpoint)
        elif mode.flag_control_rates_enabled:
            if mode.flag_control_manual_enabled and sticks is not None:
                rates = self.acro.rates(sticks.roll, sticks.pitch, sticks.yaw)
                thrust = thrust_newtons(AcroStickMapping.thrust_body(sticks.throttle), max_thrust)
                self._command(self.control.set_rates_command(rates, thrust), sticks)
            elif (rates_setpoint := self.latest(ORB_ID.vehicle_rates_setpoint)) is not None:
                rates = (rates_setpoint.roll, rates_setpoint.pitch, rates_setpoint.yaw)
                thrust = thrust_newtons(rates_setpoint.thrust_body, max_thrust)
                self._command(self.control.set_rates_command(rates, thrust), rates_setpoint)

    def _command(self, accepted: bool, source: object) -> None:
        """Count a refused setpoint once, however many cycles it stays the latest."""
        if not accepted and source is not self._refused:
            self._refused = source
            self.reject(f"a setpoint that is not finite: {source}")
