"""land_detector: PX4's multicopter land detector as a module (50 Hz), publishing vehicle_land_detected."""

from __future__ import annotations

import math

from stack.commander import land_detector
from stack.commander.land_detector import LandDetectorInputs, MulticopterLandDetector
from stack.msg.setpoints import TakeoffStatus
from stack.msg.system import VehicleLandDetected
from stack.posctl.takeoff import TakeoffState
from stack.runtime.module import Module, Timer


class LandDetectorModule(Module):
    NAME = "land_detector"
    DESCRIPTION = "Multicopter land detector (PX4 land_detector): ground contact, maybe landed, landed"
    TRIGGER = Timer(50.0)
    DT_RANGE = (0.001, 0.1)
    PARAMS = land_detector.PARAMS

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            "vehicle_local_position",
            "vehicle_angular_velocity",
            "vehicle_thrust_setpoint",
            "actuator_armed",
            "vehicle_control_mode",
            "sensor_accel",
            "trajectory_setpoint",
            "hover_thrust_estimate",
            "takeoff_status",
        ):
            self.subscribe(topic)
        self.advertise("vehicle_land_detected")
        self.detector = MulticopterLandDetector(self.params.values())

    def on_params_changed(self, changed: set[str]) -> None:
        self.detector = MulticopterLandDetector(self.params.values())

    def run(self, msg: None, dt: float) -> None:
        latest = self.latest
        inp = LandDetectorInputs()
        armed = latest("actuator_armed")
        inp.armed = armed is not None and armed.armed
        lpos = latest("vehicle_local_position")
        if lpos is not None:
            inp.local_position_timestamp_us = lpos.timestamp
            inp.z_valid, inp.v_xy_valid, inp.v_z_valid = lpos.z_valid, lpos.v_xy_valid, lpos.v_z_valid
            inp.vx, inp.vy, inp.vz, inp.z_deriv = lpos.vx, lpos.vy, lpos.vz, lpos.z_deriv
            inp.dist_bottom_valid, inp.dist_bottom = lpos.dist_bottom_valid, lpos.dist_bottom
        rates = latest("vehicle_angular_velocity")
        if rates is not None:
            inp.angular_velocity = rates.xyz
        accel = latest("sensor_accel")
        if accel is not None:
            inp.acceleration = (accel.x, accel.y, accel.z)
        thrust = latest("vehicle_thrust_setpoint")
        if thrust is not None:
            inp.throttle = -thrust.xyz[2]
        mode = latest("vehicle_control_mode")
        inp.climb_rate_control = mode is not None and mode.flag_control_climb_rate_enabled
        trajectory = latest("trajectory_setpoint")
        inp.velocity_setpoint_z = trajectory.velocity[2] if trajectory is not None else math.nan
        hover = latest("hover_thrust_estimate")
        if hover is not None and hover.valid:
            inp.hover_thrust, inp.hover_thrust_timestamp_us = hover.hover_thrust, hover.timestamp
        takeoff = latest("takeoff_status")
        if takeoff is not None and takeoff.takeoff_state >= TakeoffStatus.TAKEOFF_STATE_DISARMED:
            # takeoff_status uses PX4's numbering, one above the position controller's TakeoffState.
            inp.takeoff_state = TakeoffState(takeoff.takeoff_state - 1)
        state = self.detector.update(self.now_us(), inp)
        self.publish("vehicle_land_detected", VehicleLandDetected(**state._asdict()))
