"""Stand-in modules for `stack cmd` tests: a navigator that only answers mission uploads, and a position
estimate that holds the vehicle still at a fixed point (so the commander can arm, set home and land)."""

from __future__ import annotations

from pathlib import Path

import msgspec

from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import Mission, MissionResult
from stack.msg.registry import ORB_ID
from stack.runtime.module import Arg, Module, Timer


class MissionResponder(Module):
    """Answers every ``mission`` with a ``mission_result``: valid when it has items, else invalid with a
    reason. Appends each mission it receives to ``out``, one line of hexadecimal msgpack each."""

    NAME = "mission_responder"
    PUBLISHES = (ORB_ID.mission_result,)
    TRIGGER = Timer(20.0)
    DT_RANGE = (0.001, 0.1)
    ARGS = (Arg("out", ""),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.mission, queue=True)
        self.advertise(ORB_ID.mission_result)

    def run(self, msg: None, dt: float) -> None:
        for mission in self.take(ORB_ID.mission):
            self._record(mission)
            self.publish(
                ORB_ID.mission_result,
                MissionResult(
                    mission_id=mission.mission_id,
                    seq_total=len(mission.items),
                    valid=bool(mission.items),
                    reason="" if mission.items else "the mission has no items",
                ),
            )

    def _record(self, mission: Mission) -> None:
        if self.args["out"]:
            with Path(str(self.args["out"])).open("a") as f:
                f.write(msgspec.msgpack.encode(mission).hex() + "\n")


class FixedPosition(Module):
    """A valid local position estimate at the origin, about the geodetic reference given as arguments."""

    NAME = "fixed_position"
    PUBLISHES = (ORB_ID.vehicle_local_position,)
    TRIGGER = Timer(50.0)
    ARGS = (Arg("lat", 47.0), Arg("lon", 8.0), Arg("alt", 400.0))

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.advertise(ORB_ID.vehicle_local_position)

    def run(self, msg: None, dt: float) -> None:
        self.publish(
            ORB_ID.vehicle_local_position,
            VehicleLocalPosition(
                timestamp_sample=self.now_us(),
                xy_valid=True,
                z_valid=True,
                v_xy_valid=True,
                v_z_valid=True,
                heading_good_for_control=True,
                xy_global=True,
                z_global=True,
                ref_lat=float(self.args["lat"]),
                ref_lon=float(self.args["lon"]),
                ref_alt=float(self.args["alt"]),
                eph=0.5,
                epv=0.5,
                evh=0.1,
                evv=0.1,
            ),
        )
