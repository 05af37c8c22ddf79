"""mc_pos_control: position and velocity control on every local position estimate.

Glue around :class:`~stack.posctl.position_control.PositionControl` and
:class:`~stack.posctl.takeoff.Takeoff`, following PX4's ``MulticopterPositionControl::Run``: while
``vehicle_control_mode`` enables multicopter position control it executes the latest
``trajectory_setpoint`` (zero thrust until the takeoff ramp starts; the tilt limit and minimum
thrust of the takeoff stage; the hover thrust estimate once valid) and publishes
``vehicle_attitude_setpoint`` and ``vehicle_local_position_setpoint``. A setpoint it cannot execute
(no setpoint, invalid estimate for a controlled axis, NaN result) is replaced by PX4's failsafe
setpoint: stop, or descend blind when even the velocity estimate is gone.
"""

from __future__ import annotations

import math

from stack.estimator.acceleration import VelocityDerivative
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TakeoffState, TakeoffStatus, VehicleAttitudeSetpoint, VehicleLocalPositionSetpoint
from stack.params import catalogue
from stack.params.binding import combine
from stack.posctl.position_control import PositionControl, PositionControlParams, failsafe_setpoint
from stack.posctl.takeoff import Takeoff, TakeoffParams, wants_takeoff
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

NAN = math.nan
SETPOINT_WAIT_US = 200_000
"""How long after position control is enabled a missing trajectory setpoint is tolerated."""
SETPOINT_TIMEOUT_US = 500_000
"""A trajectory setpoint older than this no longer counts (its producer stopped)."""
TAKEOFF_STATUS_REPUBLISH_US = 1_000_000

PARAMS = combine(
    PositionControlParams.PARAMS,
    TakeoffParams.PARAMS,
    catalogue.params("MPC_USE_HTE", "MPC_VELD_LP", "MPC_LAND_SPEED"),
)


class MulticopterPositionControl(Module):
    NAME = "mc_pos_control"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Multicopter position and velocity control with smooth takeoff (PX4 mc_pos_control)"
    TRIGGER = Trigger(ORB_ID.vehicle_local_position)
    DT_RANGE = (0.002, 0.04)
    PARAMS = PARAMS

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.trajectory_setpoint,
            ORB_ID.vehicle_control_mode,
            ORB_ID.vehicle_land_detected,
            ORB_ID.hover_thrust_estimate,
        ):
            self.subscribe(topic)
        self.advertise(ORB_ID.vehicle_attitude_setpoint)
        self.advertise(ORB_ID.vehicle_local_position_setpoint)
        self.advertise(ORB_ID.takeoff_status)
        self.control = PositionControl(PositionControlParams.from_params(self.params))
        self.takeoff = Takeoff(TakeoffParams.from_params(self.params))
        self.velocity_derivative = VelocityDerivative(float(self.params["MPC_VELD_LP"]))
        self._enabled_since_us = 0
        self._first_run = True
        self._takeoff_published: tuple[int, float] | None = None
        self._takeoff_published_us = 0
        self._failsafe_action = ""
        kept = self.kept_state()
        self._kept_integral = kept.get("velocity_integral") if kept is not None else None

    def on_params_changed(self, changed: set[str]) -> None:
        self.control.set_params(PositionControlParams.from_params(self.params))
        self.takeoff.set_params(TakeoffParams.from_params(self.params))
        if "MPC_VELD_LP" in changed:
            self.velocity_derivative = VelocityDerivative(float(self.params["MPC_VELD_LP"]))

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        mode = self.latest(ORB_ID.vehicle_control_mode)
        land = self.latest(ORB_ID.vehicle_land_detected)
        armed = mode is not None and mode.flag_armed
        landed = land is None or land.landed
        vel_dot = self.velocity_derivative.update(lpos.timestamp_sample, (lpos.vx, lpos.vy, lpos.vz))
        if mode is None or not mode.flag_multicopter_position_control_enabled:
            self._enabled_since_us = 0
            # Outside position control the takeoff stage is skipped (PX4 does the same), so a switch
            # to position control in the air does not start a takeoff ramp from zero thrust.
            self.takeoff.update_state(
                lpos.timestamp_sample, armed=armed, landed=landed, want_takeoff=False, skip_takeoff=True
            )
            self._publish_takeoff_status(now)
            return
        if land is None:
            return  # restarted in flight: the takeoff state waits for the land detector's word, not "landed"
        if self._first_run:
            self._first_run = False
            # Started armed in the air (restarted after a crash): flying already, no takeoff from zero thrust.
            self.takeoff.update_state(
                lpos.timestamp_sample, armed=armed, landed=landed, want_takeoff=False, skip_takeoff=not landed
            )
        if not self._enabled_since_us:
            self._enabled_since_us = now
            self.control.reset_integral()
            if self._kept_integral is not None and not landed:
                if self.control.resume_integral(self._kept_integral):
                    self.log.info("restarted in flight: resuming the velocity integral %s", self._kept_integral)
                else:
                    self.log.warning("restarted, but the kept velocity integral is unusable: starting from zero")
            self._kept_integral = None

        position = (lpos.x if lpos.xy_valid else NAN, lpos.y if lpos.xy_valid else NAN, lpos.z if lpos.z_valid else NAN)
        velocity = (
            lpos.vx if lpos.v_xy_valid else NAN,
            lpos.vy if lpos.v_xy_valid else NAN,
            lpos.vz if lpos.v_z_valid else NAN,
        )
        accel = vel_dot if vel_dot is not None else (0.0, 0.0, 0.0)
        accel = tuple(a if math.isfinite(v) else NAN for a, v in zip(accel, velocity, strict=True))
        self.control.set_state(position, velocity, accel, lpos.heading)

        setpoint = self._fresh_setpoint(now)
        if setpoint is None and now - self._enabled_since_us < SETPOINT_WAIT_US:
            return
        sp_pos = setpoint.position if setpoint is not None else (NAN, NAN, NAN)
        sp_vel = setpoint.velocity if setpoint is not None else (NAN, NAN, NAN)
        sp_acc = setpoint.acceleration if setpoint is not None else (NAN, NAN, NAN)
        yaw = setpoint.yaw if setpoint is not None else NAN
        yawspeed = setpoint.yawspeed if setpoint is not None else NAN

        p = self.params
        state = self.takeoff.update_state(
            lpos.timestamp_sample,
            armed=armed,
            landed=landed,
            want_takeoff=wants_takeoff(sp_pos[2], sp_vel[2], position[2]),
        )
        flying = state >= TakeoffState.FLIGHT
        if not flying:
            self.control.set_hover_thrust(float(p["MPC_THR_HOVER"]))
        else:
            self._adopt_hover_thrust_estimate()
        shaped = self.takeoff.shape_setpoint(sp_pos, sp_vel, sp_acc)
        sp_pos, sp_vel, sp_acc = shaped.position, shaped.velocity, shaped.acceleration
        if flying and land is not None and land.ground_contact:
            sp_pos, sp_vel, sp_acc = (NAN, NAN, NAN), (NAN, NAN, NAN), (0.0, 0.0, 100.0)
            yaw = yawspeed = NAN
            self.control.reset_integral()
        elif shaped.reset_integral:
            yaw = yawspeed = NAN
            self.control.reset_integral()
        speed_up = self.takeoff.update_ramp(dt, float(p["MPC_Z_VEL_MAX_UP"]))
        self.control.set_limits(
            vel_horizontal=min(float(p["MPC_XY_VEL_MAX"]), lpos.vxy_max),
            vel_up=min(speed_up, float(p["MPC_Z_VEL_MAX_UP"])),
            vel_down=float(p["MPC_Z_VEL_MAX_DN"]),
            thrust_min=self.takeoff.minimum_thrust(float(p["MPC_THR_MIN"])),
            tilt_max=self.takeoff.update_tilt_limit(dt),
        )
        self.control.set_setpoint(sp_pos, sp_vel, sp_acc, yaw, yawspeed)
        if not self.control.update(dt):
            self._fly_failsafe(velocity, dt, now)
        elif self._failsafe_action:
            self.log.info("setpoint executable again; failsafe setpoint (%s) ended", self._failsafe_action)
            self._failsafe_action = ""
        self._publish_setpoints(lpos.timestamp_sample, now)
        self._publish_takeoff_status(now)
        if self.keep_due():
            self.keep_state({"velocity_integral": list(self.control.velocity_integral)})

    def _fresh_setpoint(self, now: int):
        sp = self.latest(ORB_ID.trajectory_setpoint)
        if sp is None or sp.timestamp < self._enabled_since_us or now - sp.timestamp > SETPOINT_TIMEOUT_US:
            return None
        return sp

    def _adopt_hover_thrust_estimate(self) -> None:
        if not self.params["MPC_USE_HTE"]:
            return
        hte = self.latest(ORB_ID.hover_thrust_estimate)
        if (
            hte is not None
            and hte.valid
            and math.isfinite(hte.hover_thrust)
            and abs(hte.hover_thrust - self.control.hover_thrust) > 1e-6
        ):
            self.control.update_hover_thrust(hte.hover_thrust)

    def _fly_failsafe(self, velocity, dt: float, now: int) -> None:
        fs = failsafe_setpoint(velocity, float(self.params["MPC_LAND_SPEED"]))
        if fs.action != self._failsafe_action:
            self.log.warning("setpoint not executable: failsafe setpoint (%s)", fs.action)
            self._failsafe_action = fs.action
        p = self.params
        self.control.set_limits(
            vel_horizontal=float(p["MPC_XY_VEL_MAX"]),
            vel_up=float(p["MPC_Z_VEL_MAX_UP"]),
            vel_down=float(p["MPC_Z_VEL_MAX_DN"]),
        )
        self.control.set_setpoint(fs.position, fs.velocity, fs.acceleration, NAN, NAN)
        self.control.update(dt)

    def _publish_setpoints(self, sample_us: int, now: int) -> None:
        q_d, thrust_body, yaw_rate = self.control.attitude_setpoint()
        self.publish(
            ORB_ID.vehicle_attitude_setpoint,
            VehicleAttitudeSetpoint(timestamp=now, yaw_sp_move_rate=yaw_rate, q_d=q_d, thrust_body=thrust_body),
        )
        sp = self.control.local_position_setpoint()
        self.publish(
            ORB_ID.vehicle_local_position_setpoint,
            VehicleLocalPositionSetpoint(
                timestamp=now,
                x=sp.position[0],
                y=sp.position[1],
                z=sp.position[2],
                vx=sp.velocity[0],
                vy=sp.velocity[1],
                vz=sp.velocity[2],
                acceleration=sp.acceleration,
                thrust=sp.thrust,
                yaw=sp.yaw,
                yawspeed=sp.yawspeed,
            ),
        )

    def _publish_takeoff_status(self, now: int) -> None:
        status = (int(self.takeoff.state), round(self.takeoff.tilt_limit, 4))
        if status != self._takeoff_published or now - self._takeoff_published_us >= TAKEOFF_STATUS_REPUBLISH_US:
            self._takeoff_published = status
            self._takeoff_published_us = now
            self.publish(
                ORB_ID.takeoff_status, TakeoffStatus(takeoff_state=status[0], tilt_limit=self.takeoff.tilt_limit)
            )
