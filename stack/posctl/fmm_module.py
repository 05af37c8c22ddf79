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
from stack.mission.transfer import mission_from_message
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.setpoints import TakeoffStatus, TrajectorySetpoint
from stack.posctl.flight_mode_manager import PARAMS, FlightModeManager, MissionStatus, NavigatorInputs
from stack.posctl.flight_task import VehicleState
from stack.runtime.module import Module, Trigger

NAN = math.nan
MISSION_RESULT_REPUBLISH_US = 1_000_000


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
    DESCRIPTION = "Takeoff, hold, go-to, mission, return and land as smooth trajectories (PX4 navigator + FMM)"
    TRIGGER = Trigger("vehicle_local_position")
    DT_RANGE = (0.002, 0.05)
    PARAMS = PARAMS

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            "vehicle_status",
            "navigation_request",
            "home_position",
            "takeoff_status",
            "vehicle_land_detected",
            "manual_control_setpoint",
        ):
            self.subscribe(topic)
        self.subscribe("mission", queue=True, capacity=16)
        self.advertise("trajectory_setpoint")
        self.advertise("mission_result")
        self.manager = FlightModeManager(self.params.values())
        self._published_status: MissionStatus | None = None
        self._published_us = 0

    def on_params_changed(self, changed: set[str]) -> None:
        self.manager.set_params(self.params.values())

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        for upload in self.take("mission"):
            self._load(upload)
        status = self.latest("vehicle_status")
        land = self.latest("vehicle_land_detected")
        takeoff = self.latest("takeoff_status")
        home = self.latest("home_position")
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
            request=self.latest("navigation_request"),
            manual=self.latest("manual_control_setpoint"),
        )
        command = self.manager.update(inputs, dt)
        if command is not None:
            self.publish(
                "trajectory_setpoint",
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
        self._publish_mission_result(now)

    def _load(self, upload) -> None:
        try:
            mission = mission_from_message(upload)
        except ValueError as e:
            problem = f"malformed mission: {e}"
            self.manager.load_mission_refused(upload.mission_id, problem)
        else:
            problem = self.manager.load_mission(mission, upload.mission_id)
        if problem:
            self.reject(f"mission {upload.mission_id}: {problem}")
        else:
            self.log.info("mission %d accepted: %d items", upload.mission_id, len(upload.items))
        self._published_status = None

    def _publish_mission_result(self, now: int) -> None:
        status = self.manager.mission_status()
        if status == self._published_status and now - self._published_us < MISSION_RESULT_REPUBLISH_US:
            return
        self._published_status = status
        self._published_us = now
        self.publish(
            "mission_result",
            MissionResult(
                timestamp=now,
                mission_id=status.mission_id,
                seq_reached=status.seq_reached,
                seq_current=status.seq_current,
                seq_total=status.seq_total,
                valid=status.valid,
                finished=status.finished,
                failure=not status.valid and bool(status.reason),
                reason=status.reason,
            ),
        )
