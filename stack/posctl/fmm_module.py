"""flight_mode_manager: the navigator and flight tasks, run on every local position estimate.

Glue around :class:`~stack.posctl.flight_mode_manager.FlightModeManager`: it reads the mode
(``vehicle_status``), what the commander accepted (``navigation_request``: takeoff altitude, go-to
target, mission start), home, the takeoff stage and the sticks, and publishes ``trajectory_setpoint``
for mc_pos_control. Missions arrive on ``mission``; each upload is answered on ``mission_result``,
which then reports progress (on change and every second).
"""

from __future__ import annotations

import math

from stack.commander.home import HomePosition
from stack.mission.store import MissionResultPublisher
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TakeoffStatus, TrajectorySetpoint
from stack.posctl.flight_mode_manager import PARAMS, FlightModeManager, NavigatorInputs
from stack.posctl.flight_task import VehicleState
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

NAN = math.nan


def vehicle_state(lpos: VehicleLocalPosition, landed: bool, flying: bool) -> VehicleState:
    return VehicleState(
        now_us=lpos.timestamp_sample,
        position=(lpos.x if lpos.xy_valid else NAN, lpos.y if lpos.xy_valid else NAN, lpos.z if lpos.z_valid else NAN),
        velocity=(
            lpos.vx if lpos.v_xy_valid else NAN,
            lpos.vy if lpos.v_xy_valid else NAN,
            lpos.vz if lpos.v_z_valid else NAN,
        ),
        yaw=lpos.heading,
        landed=landed,
        flying=flying,
    )


class FlightModeManagerModule(Module):
    NAME = "flight_mode_manager"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Takeoff, hold, go-to, mission, return and land as smooth trajectories (PX4 navigator + FMM)"
    TRIGGER = Trigger(ORB_ID.vehicle_local_position)
    DT_RANGE = (0.002, 0.05)
    PARAMS = PARAMS
    PUBLISHES = (ORB_ID.trajectory_setpoint, ORB_ID.mission_result)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_status,
            ORB_ID.navigation_request,
            ORB_ID.home_position,
            ORB_ID.takeoff_status,
            ORB_ID.vehicle_land_detected,
            ORB_ID.manual_control_setpoint,
        ):
            self.subscribe(topic)
        self.subscribe(ORB_ID.mission, queue=True, capacity=16)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.manager = FlightModeManager(self.params.values())
        m = self.manager
        self.results = MissionResultPublisher(m.load_mission, m.load_mission_refused, m.mission_status)

    def on_params_changed(self, changed: set[str]) -> None:
        self.manager.set_params(self.params.values())

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        self.results.take_uploads(self)
        status = self.latest(ORB_ID.vehicle_status)
        land = self.latest(ORB_ID.vehicle_land_detected)
        takeoff = self.latest(ORB_ID.takeoff_status)
        home = self.latest(ORB_ID.home_position)
        inputs = NavigatorInputs(
            state=vehicle_state(
                lpos,
                landed=land is None or land.landed,
                flying=takeoff is not None and takeoff.takeoff_state == TakeoffStatus.TAKEOFF_STATE_FLIGHT,
            ),
            nav_state=status.nav_state if status is not None else -1,
            armed=status is not None and status.arming_state == status.ARMING_STATE_ARMED,
            home=HomePosition(home.x, home.y, home.z, home.yaw, home.lat, home.lon, home.alt)
            if home is not None and home.valid_lpos
            else None,
            request=self.latest(ORB_ID.navigation_request),
            manual=self.latest(ORB_ID.manual_control_setpoint),
        )
        command = self.manager.update(inputs, dt)
        if command is not None:
            self.publish(
                ORB_ID.trajectory_setpoint,
                TrajectorySetpoint(
                    timestamp=now,
                    position=command.position,
                    velocity=command.velocity,
                    acceleration=command.acceleration,
                    jerk=command.jerk,
                    yaw=command.yaw,
                    yawspeed=command.yawspeed,
                ),
            )
        self.results.publish_result(self, now)
