"""control_allocator: torque and thrust setpoints → motor commands, run on every torque setpoint.

The allocation is built from the CA_ROTOR* geometry (rebuilt when those parameters change). Motors
idle when armed and are stopped when disarmed. The saturation of each axis goes back to the rate
loop in ``control_allocator_status``. While the land detector reports ground contact, airmode is off
(see :meth:`ControlAllocator.allocate`).
"""

from __future__ import annotations

import math

from stack.mixer import allocation, effectiveness, output
from stack.mixer.allocation import ControlAllocator
from stack.mixer.output import MotorOutput
from stack.msg.actuators import ActuatorMotors, ActuatorOutputs, ControlAllocatorStatus
from stack.msg.setpoints import VehicleTorqueSetpoint
from stack.runtime.module import Module, Trigger

OUTPUTS = 16
MOTOR_SLOTS = 12


def _pad(values: tuple[float, ...], size: int, fill: float) -> tuple[float, ...]:
    return values[:size] + (fill,) * (size - len(values))


class ControlAllocatorModule(Module):
    NAME = "control_allocator"
    DESCRIPTION = "Control allocation (PX4 control_allocator) and motor outputs"
    TRIGGER = Trigger("vehicle_torque_setpoint")
    DT_RANGE = (0.0002, 0.02)
    PARAMS = effectiveness.PARAMS + allocation.PARAMS + output.PARAMS

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe("vehicle_thrust_setpoint")
        self.subscribe("actuator_armed")
        self.subscribe("vehicle_land_detected")
        for topic in ("actuator_motors", "actuator_outputs", "actuator_outputs_sim", "control_allocator_status"):
            self.advertise(topic)
        self._build()

    def _build(self) -> None:
        values = self.params.values()
        if int(values["CA_ROTOR_COUNT"]) < 1:
            raise ValueError("CA_ROTOR_COUNT is 0: set the airframe geometry (a profile's [stack] airframe)")
        self.allocator = ControlAllocator.from_params(values)
        self.outputs = MotorOutput(self.allocator.num_motors, values)
        self.log.info("allocation for %d rotors, airmode %s", self.allocator.num_motors, values["MC_AIRMODE"])

    def on_params_changed(self, changed: set[str]) -> None:
        self._build()

    def run(self, torque_sp: VehicleTorqueSetpoint, dt: float) -> None:
        thrust_sp = self.latest("vehicle_thrust_setpoint")
        thrust = thrust_sp.xyz if thrust_sp is not None else (0.0, 0.0, 0.0)
        torque = tuple(v if math.isfinite(v) else 0.0 for v in torque_sp.xyz)
        thrust = tuple(v if math.isfinite(v) else 0.0 for v in thrust)
        armed_msg = self.latest("actuator_armed")
        armed = armed_msg is not None and armed_msg.armed and not armed_msg.lockdown and not armed_msg.kill
        land = self.latest("vehicle_land_detected")
        on_ground = land is not None and (land.ground_contact or land.maybe_landed or land.landed)
        result = self.allocator.allocate(torque, thrust, on_ground)
        out = self.outputs.update(result.motors, armed, dt)
        n = self.allocator.num_motors
        t = torque_sp.timestamp_sample
        self.publish(
            "actuator_motors",
            ActuatorMotors(timestamp_sample=t, control=_pad(out.actuator_motors, MOTOR_SLOTS, math.nan)),
        )
        self.publish("actuator_outputs", ActuatorOutputs(noutputs=n, output=_pad(out.pwm, OUTPUTS, 0.0)))
        self.publish("actuator_outputs_sim", ActuatorOutputs(noutputs=n, output=_pad(out.sim, OUTPUTS, 0.0)))
        self.publish(
            "control_allocator_status",
            ControlAllocatorStatus(
                torque_setpoint_achieved=result.torque_achieved,
                unallocated_torque=result.unallocated_torque,
                thrust_setpoint_achieved=result.thrust_achieved,
                unallocated_thrust=result.unallocated_thrust,
                actuator_saturation=_pad(result.actuator_saturation, OUTPUTS, 0),
            ),
        )
