"""mc_pos_control: position and velocity control on every local position estimate.

Glue around :class:`~stack.posctl.position_loop.PositionLoop` (PX4's ``MulticopterPositionControl::Run``): it
reads ``vehicle_control_mode``, the land detector, the latest ``trajectory_setpoint`` and the hover thrust
estimate, runs the loop, and publishes ``vehicle_attitude_setpoint`` and ``vehicle_local_position_setpoint`` when
it controls, and ``takeoff_status`` on change and every second.
"""

from __future__ import annotations

from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TakeoffStatus, VehicleAttitudeSetpoint, VehicleLocalPositionSetpoint
from stack.params import catalogue
from stack.params.binding import combine
from stack.posctl.position_control import PositionControlParams
from stack.posctl.position_loop import PositionLoop
from stack.posctl.takeoff import TakeoffParams
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

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
    PUBLISHES = (ORB_ID.vehicle_attitude_setpoint, ORB_ID.vehicle_local_position_setpoint, ORB_ID.takeoff_status)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.trajectory_setpoint,
            ORB_ID.vehicle_control_mode,
            ORB_ID.vehicle_land_detected,
            ORB_ID.hover_thrust_estimate,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        kept = self.kept_state()
        p = self.params
        self.loop = PositionLoop(
            PositionControlParams.from_params(p),
            TakeoffParams.from_params(p),
            use_hover_thrust_estimate=bool(p["MPC_USE_HTE"]),
            land_speed=float(p["MPC_LAND_SPEED"]),
            velocity_derivative_cutoff=float(p["MPC_VELD_LP"]),
            kept_integral=kept.get("velocity_integral") if kept is not None else None,
        )
        self.control = self.loop.control
        self.takeoff = self.loop.takeoff
        self._takeoff_published: tuple[int, float] | None = None
        self._takeoff_published_us = 0
        self._failsafe_action = ""

    def on_params_changed(self, changed: set[str]) -> None:
        p = self.params
        self.loop.set_params(
            PositionControlParams.from_params(p),
            TakeoffParams.from_params(p),
            use_hover_thrust_estimate=bool(p["MPC_USE_HTE"]),
            land_speed=float(p["MPC_LAND_SPEED"]),
            velocity_derivative_cutoff=float(p["MPC_VELD_LP"]) if "MPC_VELD_LP" in changed else None,
        )

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        mode = self.latest(ORB_ID.vehicle_control_mode)
        enabled = mode is not None and mode.flag_multicopter_position_control_enabled
        result = self.loop.update(
            now,
            dt,
            lpos,
            enabled=enabled,
            armed=mode is not None and mode.flag_armed,
            land=self.latest(ORB_ID.vehicle_land_detected),
            setpoint=self.latest(ORB_ID.trajectory_setpoint),
            hover_thrust_estimate=self.latest(ORB_ID.hover_thrust_estimate),
        )
        if result.resumed_integral is True:
            self.log.info("restarted in flight: resuming the velocity integral %s", self.control.velocity_integral)
        elif result.resumed_integral is False:
            self.log.warning("restarted, but the kept velocity integral is unusable: starting from zero")
        if self.loop.failsafe_action != self._failsafe_action:
            if self.loop.failsafe_action:
                self.log.warning("setpoint not executable: failsafe setpoint (%s)", self.loop.failsafe_action)
            else:
                self.log.info("setpoint executable again; failsafe setpoint (%s) ended", self._failsafe_action)
            self._failsafe_action = self.loop.failsafe_action
        if result.setpoints:
            self._publish_setpoints(now)
        if result.setpoints or not enabled:
            self._publish_takeoff_status(now)
        if result.setpoints and self.keep_due():
            self.keep_state({"velocity_integral": list(self.control.velocity_integral)})

    def _publish_setpoints(self, now: int) -> None:
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
