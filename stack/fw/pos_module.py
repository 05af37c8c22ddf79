"""fw_pos_control: fixed-wing position control, run on every local position estimate (PX4 fw_pos_control_l1).

Glue around :class:`~stack.fw.pos_control.FixedwingPositionControl`: it reads the mode (``vehicle_status``),
the navigator's ``position_setpoint_triplet``, the attitude, ``airspeed_validated``, the ``wind`` estimate,
the land detector and the sticks, and publishes ``vehicle_attitude_setpoint`` (roll, pitch, heading, throttle in
thrust_body[0], wheel steering, integrator reset) for fw_att_control, with ``tecs_status`` and
``position_controller_status`` (the waypoint switching distance the navigator uses).
"""

from __future__ import annotations

import math

import msgspec

from stack.fw.pos_control import PARAMS, FwPosInputs
from stack.fw.pos_control import FixedwingPositionControl as PositionController
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.fixedwing import AIRSPEED_TIMEOUT_US, PositionControllerStatus
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleAttitudeSetpoint
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

NAN = math.nan


class FixedwingPositionControl(Module):
    NAME = "fw_pos_control"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Fixed-wing position control (PX4 fw_pos_control_l1): L1 or NPFG, TECS, runway takeoff, landing"
    TRIGGER = Trigger(ORB_ID.vehicle_local_position)
    DT_RANGE = (0.002, 0.1)
    PARAMS = PARAMS
    PUBLISHES = (ORB_ID.vehicle_attitude_setpoint, ORB_ID.tecs_status, ORB_ID.position_controller_status)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_status,
            ORB_ID.vehicle_attitude,
            ORB_ID.airspeed_validated,
            ORB_ID.wind,
            ORB_ID.position_setpoint_triplet,
            ORB_ID.manual_control_setpoint,
            ORB_ID.vehicle_land_detected,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.control = PositionController(self.params.values())

    def on_params_changed(self, changed: set[str]) -> None:
        self.control.set_params(self.params.values())

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        status = self.latest(ORB_ID.vehicle_status)
        attitude = self.latest(ORB_ID.vehicle_attitude)
        if status is None or attitude is None or not quat.is_finite(attitude.q):
            return
        roll, pitch, yaw = quat.to_euler(attitude.q)
        airspeed, eas_to_tas = NAN, 1.0
        measured = self.latest(ORB_ID.airspeed_validated)
        if measured is not None and now - measured.timestamp <= AIRSPEED_TIMEOUT_US:
            airspeed = measured.calibrated_airspeed_m_s
            if measured.calibrated_airspeed_m_s > 0.0 and math.isfinite(measured.true_airspeed_m_s):
                eas_to_tas = measured.true_airspeed_m_s / measured.calibrated_airspeed_m_s
        wind = self.latest(ORB_ID.wind)
        wind_ne = (NAN, NAN)
        if wind is not None and now - wind.timestamp <= AIRSPEED_TIMEOUT_US:
            wind_ne = (wind.windspeed_north, wind.windspeed_east)
        land = self.latest(ORB_ID.vehicle_land_detected)
        out = self.control.update(
            FwPosInputs(
                now_us=lpos.timestamp_sample,
                dt=dt,
                nav_state=status.nav_state,
                armed=status.arming_state == status.ARMING_STATE_ARMED,
                landed=land is None or land.landed,
                position=(
                    lpos.x if lpos.xy_valid else NAN,
                    lpos.y if lpos.xy_valid else NAN,
                    lpos.z if lpos.z_valid else NAN,
                ),
                velocity=(
                    lpos.vx if lpos.v_xy_valid else NAN,
                    lpos.vy if lpos.v_xy_valid else NAN,
                    lpos.vz if lpos.v_z_valid else NAN,
                ),
                acceleration=(lpos.ax, lpos.ay, lpos.az),
                roll=roll,
                pitch=pitch,
                yaw=yaw,
                airspeed=airspeed,
                eas_to_tas=eas_to_tas,
                wind=wind_ne,
                triplet=self.latest(ORB_ID.position_setpoint_triplet),
                manual=self.latest(ORB_ID.manual_control_setpoint),
            )
        )
        if out is None:
            return
        self.publish(
            ORB_ID.vehicle_attitude_setpoint,
            VehicleAttitudeSetpoint(
                timestamp=now,
                q_d=quat.from_euler(out.roll, out.pitch, out.yaw),
                thrust_body=(out.throttle, 0.0, 0.0),
                fw_control_yaw_wheel=out.wheel_steering,
                reset_integral=out.reset_integral,
            ),
        )
        self.publish(ORB_ID.tecs_status, msgspec.structs.replace(self.control.tecs.status(), timestamp=now))
        s = self.control.status
        self.publish(
            ORB_ID.position_controller_status,
            PositionControllerStatus(
                timestamp=now,
                nav_roll=s.nav_roll,
                nav_bearing=s.nav_bearing,
                target_bearing=s.target_bearing,
                xtrack_error=s.xtrack_error,
                wp_dist=s.wp_dist,
                acceptance_radius=s.acceptance_radius,
                type=s.type,
            ),
        )
