"""A commander flying a plane (MAV_TYPE 1) whose airspeed sensor and selector keep reporting."""

from __future__ import annotations

import dataclasses

from stack.commander import commands as C
from stack.commander.control_chain import FW_CHAIN
from stack.commander.state_machine import Commander
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import Clock

MAV_TYPE_FIXED_WING = 1


class PlaneClock(Clock):
    """A :class:`Clock` whose inputs carry a fresh airspeed (``airspeed``: the calibrated airspeed, NaN for
    an invalid one; ``airspeed_fresh`` False: none arrives)."""

    def __init__(self, commander: Commander) -> None:
        self.airspeed = 0.0
        self.airspeed_fresh = True
        super().__init__(commander)

    def inputs(self):
        inputs = super().inputs()
        if not self.airspeed_fresh:
            return inputs
        return dataclasses.replace(
            inputs,
            airspeed_timestamp_us=self.t,
            airspeed_validated_timestamp_us=self.t,
            calibrated_airspeed=self.airspeed,
        )

    def keep_alive(self, seconds: float, but: str = "") -> None:
        """Step while every output of the fixed-wing chain but ``but``'s keeps coming."""
        end = self.t + max(round(seconds * 1e6), self.period)
        while self.t < end:
            for link in FW_CHAIN:
                if link.module != but:
                    self.commander.chain.output_seen(link.output, self.t)
            self.step()


def plane_clock(**params) -> PlaneClock:
    """A plane's commander (failsafe delay off unless given) on a 100 Hz clock."""
    return PlaneClock(Commander({"COM_FAIL_ACT_T": 0.0, "MAV_TYPE": MAV_TYPE_FIXED_WING, **params}))


def flying_plane(sticks: bool = False, **params) -> PlaneClock:
    """A plane in Hold at 50 m above home, 15 m/s through the air, its whole chain reporting (and manual control
    input arriving with ``sticks``)."""
    clock = plane_clock(**params)
    clock.sticks = sticks
    clock.step()
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.send(C.set_mode_command("hold")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.airspeed = 15.0
    clock.fly_to((0.0, 0.0, -50.0))
    clock.keep_alive(0.05)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    return clock
