"""rotors_joy_interface: the sticks as RotorS' roll, pitch, yaw-rate and thrust command, in the RotorS mode.

RotorS' ``rotors_joy_interface`` (``rotors_joy_interface/src/joy.cpp``, ethz-asl/rotors_simulator) publishes a
``command/roll_pitch_yawrate_thrust`` for each joystick message; here each cycle maps the latest
``manual_control_setpoint`` with :class:`stack.attctl.rotors_joy.JoyMapping` onto
``roll_pitch_yawrate_thrust_setpoint``, which roll_pitch_yawrate_thrust_controller follows. It runs on a timer rather
than on the sticks, so that sticks from outside a lockstep run (a ground station) count, and so that its output is
the heartbeat the commander watches while the mode runs: lost sticks are the commander's manual-control-loss
failsafe, not a silent controller. Outside the RotorS mode, or without valid sticks, it publishes nothing.
"""

from __future__ import annotations

from stack.attctl import rotors_joy
from stack.attctl.rotors_joy import JoyMapping
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import RollPitchYawrateThrustSetpoint
from stack.runtime.module import Module, Timer
from stack.runtime.priority import HP_DEFAULT

RATE_HZ = 100.0


class RotorsJoyInterface(Module):
    NAME = "rotors_joy_interface"
    WORK_QUEUE = HP_DEFAULT
    DESCRIPTION = "RotorS joystick interface: sticks → roll, pitch, yaw rate and thrust setpoint (RotorS mode)"
    TRIGGER = Timer(RATE_HZ)
    DT_RANGE = (0.001, 0.1)
    PARAMS = rotors_joy.PARAMS
    PUBLISHES = (ORB_ID.roll_pitch_yawrate_thrust_setpoint,)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.manual_control_setpoint)
        self.subscribe(ORB_ID.vehicle_control_mode)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.joy = JoyMapping(self.params.values())

    def on_params_changed(self, changed: set[str]) -> None:
        self.joy.set_params(self.params.values())

    def run(self, msg: None, dt: float) -> None:
        mode = self.latest(ORB_ID.vehicle_control_mode)
        sticks = self.latest(ORB_ID.manual_control_setpoint)
        if mode is None or not mode.flag_control_rpyt_enabled or sticks is None or not sticks.valid:
            return
        command = self.joy.command(sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle)
        self.publish(
            ORB_ID.roll_pitch_yawrate_thrust_setpoint,
            RollPitchYawrateThrustSetpoint(timestamp_sample=sticks.timestamp_sample, **command._asdict()),
        )
