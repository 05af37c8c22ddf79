"""COM_EXT_AP: the commander with an external autopilot (a Pixhawk through the pixhawk module) as the plant.

Arming needs the autopilot's link (and its pre-arm checks when it is in Offboard already); an arming command is
answered once the autopilot has armed, or refused with its reason; the autopilot's own disarming disarms the
stack; while its link is down the stack's estimate failsafes wait (the autopilot's own failsafe flies).
"""

from __future__ import annotations

import dataclasses

from stack.commander import commands as C
from stack.commander.state_machine import EXTERNAL_ARM_TIMEOUT_US, Commander
from stack.msg.system import ExternalAutopilotStatus
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import Clock, healthy

CONNECTED = {"connected": True, "armable": True, "mode": "POSCTL"}
IN_CONTROL = {"connected": True, "armed": True, "offboard": True, "in_control": True, "mode": "OFFBOARD"}


class PixhawkClock(Clock):
    """A commander with COM_EXT_AP whose external autopilot reports ``ext`` (fresh every cycle; None: silent)."""

    def __init__(self, **params) -> None:
        self.ext: dict[str, object] | None = dict(CONNECTED)
        self.stale = False
        self.acks: list[ACK] = []
        super().__init__(Commander({"COM_FAIL_ACT_T": 0.0, "COM_EXT_AP": 1, **params}))

    def inputs(self):
        inputs = healthy(self.t, self.position, self.landed, **self.overrides)
        if self.ext is None:
            return inputs
        stamp = self.t - 2_000_000 if self.stale else self.t
        return dataclasses.replace(inputs, external_autopilot=ExternalAutopilotStatus(timestamp=stamp, **self.ext))

    def step(self, seconds: float = 0.0):
        end = self.t + max(round(seconds * 1e6), self.period)
        while self.t < end:
            self.t += self.period
            self.last = self.commander.update(self.t, self.inputs())
            self.events.extend(self.last.events)
            self.acks.extend(self.last.acks)
        return self.last

    def send(self, cmd):
        self.commander.set_inputs(self.t, self.inputs())
        return self.commander.handle_command(cmd, self.t)


def test_arming_needs_the_autopilots_link():
    clock = PixhawkClock()
    clock.ext = None
    clock.step()
    ack = clock.send(C.arm_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Arming denied: no link to the external autopilot (Pixhawk)"
    clock.ext, clock.stale = dict(CONNECTED), True
    clock.step()
    assert "no link" in clock.send(C.arm_command()).reason
    clock.ext = {**CONNECTED, "connected": False}
    clock.stale = False
    clock.step()
    assert "no link" in clock.send(C.arm_command()).reason


def test_the_autopilots_prearm_check_counts_in_offboard():
    clock = PixhawkClock()
    clock.ext = {"connected": True, "armable": False, "offboard": True, "mode": "OFFBOARD"}
    clock.step()
    ack = clock.send(C.arm_command())
    assert ack.reason == "Arming denied: the Pixhawk's pre-arm checks fail in OFFBOARD"
    clock.ext = {"connected": True, "armable": False, "mode": "POSCTL"}  # another mode: its verdict is for that one
    clock.step()
    assert clock.send(C.arm_command()) is None


def test_an_arming_is_answered_once_the_autopilot_has_armed():
    clock = PixhawkClock()
    clock.step()
    assert clock.send(C.takeoff_command(5.0)) is None  # held: the stack armed, the Pixhawk not yet
    assert clock.step().vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    clock.step(0.5)
    assert clock.acks == []
    clock.ext = dict(IN_CONTROL)
    clock.step()
    (ack,) = clock.acks
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED and ack.command == C.takeoff_command(5.0).command
    assert "Pixhawk armed in OFFBOARD" in clock.events
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF


def test_a_refusal_by_the_autopilot_is_a_refusal_with_its_reason():
    clock = PixhawkClock()
    clock.step()
    assert clock.send(C.arm_command()) is None
    clock.ext = {**CONNECTED, "refusals": 1, "refusal": "the Pixhawk refused to arm: denied: Arming denied: x"}
    clock.step()
    (ack,) = clock.acks
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Arming denied: the Pixhawk refused to arm: denied: Arming denied: x"
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED


def test_an_autopilot_that_does_not_arm_in_time_is_a_refusal():
    clock = PixhawkClock()
    clock.step()
    assert clock.send(C.arm_command()) is None
    clock.step(EXTERNAL_ARM_TIMEOUT_US / 1e6 + 0.05)
    (ack,) = clock.acks
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert "did not arm within 1.5 s (no confirmation)" in ack.reason
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED


def test_a_disarm_before_the_autopilot_armed_cancels_the_held_answer():
    clock = PixhawkClock()
    clock.step()
    assert clock.send(C.arm_command()) is None
    assert clock.send(C.disarm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.step()
    (ack,) = clock.acks
    assert ack.result == 6  # MAV_RESULT_CANCELLED


def flying() -> PixhawkClock:
    clock = PixhawkClock()
    clock.step()
    clock.send(C.takeoff_command(5.0))
    clock.ext = dict(IN_CONTROL)
    clock.step()
    clock.fly_to((0.0, 0.0, -5.0))
    clock.step(1.0)
    assert clock.acks[0].result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    return clock


def test_the_autopilot_disarming_on_its_own_disarms_the_stack():
    clock = flying()
    clock.ext = {**IN_CONTROL, "armed": False, "in_control": False, "mode": "AUTO.LAND"}
    clock.step()
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED
    assert "The Pixhawk disarmed on its own (in AUTO.LAND): disarmed" in clock.events


def test_estimate_failsafes_wait_while_the_autopilots_link_is_down():
    clock = flying()
    clock.ext = {**IN_CONTROL, "connected": False}
    stale = clock.t
    clock.overrides = {"attitude_timestamp_us": stale, "angular_velocity_timestamp_us": stale}
    clock.step(3.0)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER and not clock.status.failsafe
    assert any(e.startswith("Link to the Pixhawk lost") for e in clock.events)
    clock.ext = dict(IN_CONTROL)
    clock.overrides = {}
    clock.step(2.0)  # back, with fresh estimates within the grace
    assert "Link to the Pixhawk regained" in clock.events and not clock.status.failsafe
    clock.overrides = {"attitude_timestamp_us": clock.t, "angular_velocity_timestamp_us": clock.t}
    clock.step(2.0)  # link up, estimates stale: the stack's own failsafe acts
    assert clock.status.failsafe
