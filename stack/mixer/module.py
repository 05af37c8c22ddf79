"""control_allocator: torque and thrust setpoints → actuator commands, run on every torque setpoint.

CA_AIRFRAME chooses the allocation, rebuilt when its parameters change:

- 0, multirotor: from the CA_ROTOR* geometry. Motors idle when armed and are stopped when disarmed. The saturation
  of each axis goes back to the rate loop in ``control_allocator_status``. While a descent is demanded and on the
  ground, airmode is off (:func:`stack.mixer.allocation.thrust_has_priority`).
- 1, fixed wing: the CA_ROTOR* motors pushing forward, then the CA_SV_CS* control surfaces
  (:mod:`stack.mixer.fixedwing`). ``actuator_motors`` carries the motors, ``actuator_servos`` the surfaces, and
  the outputs list the motors then the surfaces (the default plane: throttle, aileron, elevator, rudder).
  Disarmed: motors stopped, surfaces centred.
"""

from __future__ import annotations

import math

from stack.mathlib.vector import Vec3
from stack.mixer import allocation, effectiveness, fixedwing, output
from stack.mixer.allocation import ControlAllocator
from stack.mixer.fixedwing import FixedWingAllocator
from stack.mixer.output import MotorOutput, servo_outputs
from stack.msg.actuators import MOTOR_SLOTS, OUTPUT_SLOTS, ActuatorMotors, ActuatorOutputs, ControlAllocatorStatus, pad
from stack.msg.fixedwing import SERVO_SLOTS, ActuatorServos
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleTorqueSetpoint
from stack.params import ca
from stack.params.binding import combine
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import RATE_CTRL


class ControlAllocatorModule(Module):
    NAME = "control_allocator"
    WORK_QUEUE = RATE_CTRL
    DESCRIPTION = "Control allocation (PX4 control_allocator) and motor and servo outputs"
    TRIGGER = Trigger(ORB_ID.vehicle_torque_setpoint)
    DT_RANGE = (0.0002, 0.02)
    PARAMS = combine(effectiveness.PARAMS, allocation.PARAMS, output.PARAMS, ca.AIRFRAME_PARAMS, fixedwing.PARAMS)
    PUBLISHES = (
        ORB_ID.actuator_motors,
        ORB_ID.actuator_outputs,
        ORB_ID.actuator_outputs_sim,
        ORB_ID.control_allocator_status,
        ORB_ID.actuator_servos,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_thrust_setpoint)
        self.subscribe(ORB_ID.actuator_armed)
        self.subscribe(ORB_ID.vehicle_land_detected)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self._build()

    def _build(self) -> None:
        values = self.params.values()
        if int(values["CA_ROTOR_COUNT"]) < 1:
            raise ValueError("CA_ROTOR_COUNT is 0: set the airframe geometry (a profile's [stack] airframe)")
        self.plane: FixedWingAllocator | None = None
        if int(values["CA_AIRFRAME"]) == ca.AIRFRAME_FIXED_WING:
            self.plane = FixedWingAllocator.from_params(values)
            if self.plane.num_motors + self.plane.num_surfaces > OUTPUT_SLOTS:
                raise ValueError(f"CA_ROTOR_COUNT + CA_SV_CS_COUNT exceeds the {OUTPUT_SLOTS} outputs")
            self.outputs = MotorOutput(self.plane.num_motors, values, idle=False)
            self.log.info(
                "fixed-wing allocation: %d motors, %d control surfaces", self.plane.num_motors, self.plane.num_surfaces
            )
            return
        self.allocator = ControlAllocator.from_params(values)
        self.outputs = MotorOutput(self.allocator.num_motors, values)
        self.log.info("allocation for %d rotors, airmode %s", self.allocator.num_motors, values["MC_AIRMODE"])

    def on_params_changed(self, changed: set[str]) -> None:
        self._build()

    def run(self, torque_sp: VehicleTorqueSetpoint, dt: float) -> None:
        thrust_sp = self.latest(ORB_ID.vehicle_thrust_setpoint)
        thrust = thrust_sp.xyz if thrust_sp is not None else (0.0, 0.0, 0.0)
        torque = tuple(v if math.isfinite(v) else 0.0 for v in torque_sp.xyz)
        thrust = tuple(v if math.isfinite(v) else 0.0 for v in thrust)
        armed_msg = self.latest(ORB_ID.actuator_armed)
        armed = armed_msg is not None and armed_msg.armed and not armed_msg.lockdown and not armed_msg.kill
        if self.plane is not None:
            self._run_fixed_wing(self.plane, torque_sp.timestamp_sample, torque, thrust, armed, dt)
            return
        priority = allocation.thrust_has_priority(self.latest(ORB_ID.vehicle_land_detected))
        result = self.allocator.allocate(torque, thrust, priority)
        out = self.outputs.update(result.motors, armed, dt)
        n = self.allocator.num_motors
        t = torque_sp.timestamp_sample
        self.publish(
            ORB_ID.actuator_motors,
            ActuatorMotors(timestamp_sample=t, control=pad(out.actuator_motors, MOTOR_SLOTS, math.nan)),
        )
        self.publish(ORB_ID.actuator_outputs, ActuatorOutputs(noutputs=n, output=pad(out.pwm, OUTPUT_SLOTS, 0.0)))
        self.publish(ORB_ID.actuator_outputs_sim, ActuatorOutputs(noutputs=n, output=pad(out.sim, OUTPUT_SLOTS, 0.0)))
        self.publish(
            ORB_ID.control_allocator_status,
            ControlAllocatorStatus(
                torque_setpoint_achieved=result.torque_achieved,
                unallocated_torque=result.unallocated_torque,
                thrust_setpoint_achieved=result.thrust_achieved,
                unallocated_thrust=result.unallocated_thrust,
                actuator_saturation=pad(result.actuator_saturation, OUTPUT_SLOTS, 0),
            ),
        )

    def _run_fixed_wing(
        self, plane: FixedWingAllocator, t: int, torque: Vec3, thrust: Vec3, armed: bool, dt: float
    ) -> None:
        result = plane.allocate(torque, thrust)
        motors = self.outputs.update(result.motors, armed, dt)
        servos = servo_outputs(result.servos, armed)
        n = plane.num_motors + plane.num_surfaces
        self.publish(
            ORB_ID.actuator_motors,
            ActuatorMotors(timestamp_sample=t, control=pad(motors.actuator_motors, MOTOR_SLOTS, math.nan)),
        )
        self.publish(
            ORB_ID.actuator_servos,
            ActuatorServos(timestamp_sample=t, control=pad(servos.actuator_servos, SERVO_SLOTS, math.nan)),
        )
        pwm = pad(motors.pwm + servos.pwm, OUTPUT_SLOTS, 0.0)
        self.publish(ORB_ID.actuator_outputs, ActuatorOutputs(noutputs=n, output=pwm))
        sim = pad(motors.sim + servos.sim, OUTPUT_SLOTS, 0.0)
        self.publish(ORB_ID.actuator_outputs_sim, ActuatorOutputs(noutputs=n, output=sim))
        self.publish(
            ORB_ID.control_allocator_status,
            ControlAllocatorStatus(
                torque_setpoint_achieved=result.torque_achieved,
                unallocated_torque=result.unallocated_torque,
                thrust_setpoint_achieved=result.thrust_achieved,
                unallocated_thrust=result.unallocated_thrust,
                actuator_saturation=pad(result.actuator_saturation, OUTPUT_SLOTS, 0),
            ),
        )
