"""navigator: the fixed-wing navigator, run on every local position estimate.

Glue around :class:`~stack.fw.navigator.FixedwingNavigator`: it reads the mode (``vehicle_status``), what the
commander accepted (``navigation_request``), home, the land detector and the guidance's switching distance
(``position_controller_status``), and publishes ``position_setpoint_triplet`` for fw_pos_control. Missions
arrive on ``mission`` and are answered on ``mission_result`` exactly as the multicopter's flight-mode manager
answers them.
"""

from __future__ import annotations

import math

import msgspec

from stack.commander.home import HomePosition
from stack.fw.navigator import PARAMS, FixedwingNavigator, FwNavigatorInputs
from stack.mission.store import MissionResultPublisher
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import HP_DEFAULT

NAN = math.nan


class NavigatorModule(Module):
    NAME = "navigator"
    WORK_QUEUE = HP_DEFAULT
    DESCRIPTION = "Fixed-wing navigator: takeoff, hold, mission, return and land as a position-setpoint triplet"
    TRIGGER = Trigger(ORB_ID.vehicle_local_position)
    DT_RANGE = (0.002, 0.05)
    PARAMS = PARAMS
    PUBLISHES = (ORB_ID.position_setpoint_triplet, ORB_ID.mission_result)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_status,
            ORB_ID.navigation_request,
            ORB_ID.home_position,
            ORB_ID.vehicle_land_detected,
            ORB_ID.position_controller_status,
        ):
            self.subscribe(topic)
        self.subscribe(ORB_ID.mission, queue=True, capacity=16)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.navigator = FixedwingNavigator(self.params.values())
        store = self.navigator.missions
        self.results = MissionResultPublisher(
            lambda mission, mission_id: store.load(mission, mission_id, self.params.values()),
            store.refuse,
            store.status,
        )

    def on_params_changed(self, changed: set[str]) -> None:
        self.navigator.set_params(self.params.values())

    def run(self, lpos: VehicleLocalPosition, dt: float) -> None:
        now = self.now_us()
        self.results.take_uploads(self)
        status = self.latest(ORB_ID.vehicle_status)
        land = self.latest(ORB_ID.vehicle_land_detected)
        home = self.latest(ORB_ID.home_position)
        guidance = self.latest(ORB_ID.position_controller_status)
        triplet = self.navigator.update(
            FwNavigatorInputs(
                now_us=lpos.timestamp_sample,
                nav_state=status.nav_state if status is not None else -1,
                armed=status is not None and status.arming_state == status.ARMING_STATE_ARMED,
                landed=land is None or land.landed,
                position=(
                    lpos.x if lpos.xy_valid else NAN,
                    lpos.y if lpos.xy_valid else NAN,
                    lpos.z if lpos.z_valid else NAN,
                ),
                yaw=lpos.heading,
                home=HomePosition(home.x, home.y, home.z, home.yaw, home.lat, home.lon, home.alt)
                if home is not None and home.valid_lpos
                else None,
                request=self.latest(ORB_ID.navigation_request),
                acceptance_radius=guidance.acceptance_radius if guidance is not None else NAN,
            )
        )
        if triplet is not None:
            self.publish(ORB_ID.position_setpoint_triplet, msgspec.structs.replace(triplet, timestamp=now))
        self.results.publish_result(self, now)
