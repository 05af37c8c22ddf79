"""mc_hover_thrust_estimator: learns the collective thrust that holds altitude, on every local position.

It compares the estimator's vertical acceleration with the thrust the position controller asked
for (``vehicle_local_position_setpoint``) while armed and in the air, and publishes
``hover_thrust_estimate``, which the position controller adopts once valid, so the vehicle holds
altitude whatever its mass.
"""

from __future__ import annotations

from stack.msg.registry import ORB_ID
from stack.msg.setpoints import HoverThrustEstimate
from stack.posctl.hover_thrust_estimator import HoverThrustEstimator, HoverThrustEstimatorParams
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

PARAMS = HoverThrustEstimatorParams.PARAMS


class HoverThrustEstimatorModule(Module):
    NAME = "mc_hover_thrust_estimator"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Hover thrust estimation from vertical acceleration and thrust (PX4 mc_hover_thrust_estimator)"
    TRIGGER = Trigger(ORB_ID.vehicle_local_position)
    DT_RANGE = (0.002, 0.1)
    PARAMS = PARAMS
    PUBLISHES = (ORB_ID.hover_thrust_estimate,)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_local_position_setpoint)
        self.subscribe(ORB_ID.vehicle_land_detected)
        self.subscribe(ORB_ID.actuator_armed)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.estimator = HoverThrustEstimator(HoverThrustEstimatorParams.from_params(self.params))

    def on_params_changed(self, changed: set[str]) -> None:
        self.estimator.set_params(HoverThrustEstimatorParams.from_params(self.params))

    def run(self, lpos, dt: float) -> None:
        armed = self.latest(ORB_ID.actuator_armed)
        land = self.latest(ORB_ID.vehicle_land_detected)
        setpoint = self.latest(ORB_ID.vehicle_local_position_setpoint)
        thrust_z = setpoint.thrust[2] if setpoint is not None else float("nan")
        estimate = self.estimator.update(
            lpos.timestamp_sample,
            armed=armed is not None and armed.armed,
            in_air=land is not None and not land.landed,
            velocity=(lpos.vx, lpos.vy, lpos.vz),
            acc_z=lpos.az if lpos.v_z_valid else float("nan"),
            thrust_z=thrust_z,
        )
        self.publish(
            ORB_ID.hover_thrust_estimate,
            HoverThrustEstimate(timestamp_sample=lpos.timestamp_sample, **estimate._asdict()),
        )
