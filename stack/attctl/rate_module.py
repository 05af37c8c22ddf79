"""mc_rate_control: the body-rate loop, run on every filtered angular velocity sample.

PX4's RateControl (``src/lib/rate_control/rate_control.cpp``): PID with feed-forward, the integrator held
back on an axis the allocator reports saturated (``control_allocator_status``, read as
``MulticopterRateControl.cpp`` reads it) and while landed, and D on the measured angular acceleration. Its
torque and thrust setpoints go to the allocator (thrust first, so the allocator, triggered by the torque,
always sees the thrust of the same step).
"""

from __future__ import annotations

from stack.attctl import rate_control
from stack.attctl.rate_control import RateControl, YawTorqueLowPass, saturation_from_allocator
from stack.msg.estimation import VehicleAngularVelocity
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import RateCtrlStatus, VehicleThrustSetpoint, VehicleTorqueSetpoint
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import RATE_CTRL


class MulticopterRateControl(Module):
    NAME = "mc_rate_control"
    WORK_QUEUE = RATE_CTRL
    DESCRIPTION = "Body-rate controller (PX4 mc_rate_control): rate setpoint → torque and thrust setpoints"
    TRIGGER = Trigger(ORB_ID.vehicle_angular_velocity)
    DT_RANGE = (0.000125, 0.02)
    PARAMS = rate_control.PARAMS
    PUBLISHES = (ORB_ID.vehicle_thrust_setpoint, ORB_ID.vehicle_torque_setpoint, ORB_ID.rate_ctrl_status)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_rates_setpoint,
            ORB_ID.control_allocator_status,
            ORB_ID.vehicle_control_mode,
            ORB_ID.vehicle_land_detected,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.control = RateControl(self.params.values())
        self.yaw_filter = YawTorqueLowPass(float(self.params["MC_YAW_TQ_CUTOFF"]))

    def on_params_changed(self, changed: set[str]) -> None:
        self.control.set_params(self.params.values())
        self.yaw_filter.set_cutoff(float(self.params["MC_YAW_TQ_CUTOFF"]))

    def run(self, rates: VehicleAngularVelocity, dt: float) -> None:
        mode = self.latest(ORB_ID.vehicle_control_mode)
        if mode is None or not mode.flag_control_rates_enabled:
            return
        status = self.update(ORB_ID.control_allocator_status)
        if status is not None:
            self.control.set_saturation_status(
                *saturation_from_allocator(status.torque_setpoint_achieved, status.unallocated_torque)
            )
        if not mode.flag_armed:
            self.control.reset_integral()
            self.yaw_filter.reset()
        land = self.latest(ORB_ID.vehicle_land_detected)
        landed = land is not None and (land.landed or land.maybe_landed)
        sp = self.latest(ORB_ID.vehicle_rates_setpoint)
        if sp is None:
            return
        if sp.reset_integral:
            self.control.reset_integral()
        torque = self.control.update(rates.xyz, (sp.roll, sp.pitch, sp.yaw), rates.xyz_derivative, dt, landed)
        torque = (torque[0], torque[1], self.yaw_filter.update(torque[2], dt))
        thrust = tuple(t if t == t else 0.0 for t in sp.thrust_body)
        t = rates.timestamp_sample
        self.publish(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(timestamp_sample=t, xyz=thrust))
        self.publish(ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp_sample=t, xyz=torque))
        i = self.control.integral
        self.publish(
            ORB_ID.rate_ctrl_status, RateCtrlStatus(rollspeed_integ=i[0], pitchspeed_integ=i[1], yawspeed_integ=i[2])
        )
