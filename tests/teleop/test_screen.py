"""The screen: the vehicle's state, the sticks with what they mean in the RotorS mode, answers, the keys."""

import math

from stack.attctl.rotors_joy import JoyMapping
from stack.cli.vehicle_summary import summary
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import BatteryStatus, HomePosition
from stack.msg.system import VehicleStatus as NS
from stack.teleop.gamepad import DEFAULT_MAPPING, load_mapping
from stack.teleop.screen import Frame, gamepad_keys, keyboard_keys, render
from stack.teleop.sticks import Sticks


def frame(**changes) -> Frame:
    latest = {
        "vehicle_status": NS(nav_state=NS.NAVIGATION_STATE_POSCTL, arming_state=NS.ARMING_STATE_ARMED),
        "vehicle_local_position": VehicleLocalPosition(z=-5.04, xy_valid=True, z_valid=True),
        "home_position": HomePosition(z=0.0, valid_lpos=True),
        "battery_status": BatteryStatus(voltage_v=15.83, remaining=0.92),
    }
    f = Frame(
        vehicle="v1",
        clock="real time",
        summary=summary(latest, None),
        velocity=(3.0, 4.0, -0.5),
        sticks=Sticks(0.3, -0.5, 0.0, 0.0),
        source="keyboard, stick limit 50 %",
        sending=True,
        subscribed=True,
        rate_hz=49.96,
        silent_s=0.1,
        keys=keyboard_keys(),
        answer="mode Position: accepted",
        commands=2,
        said=["Mode: Position"],
    )
    for k, v in changes.items():
        setattr(f, k, v)
    return f


def test_the_vehicle_the_sticks_and_the_keys():
    lines = render(frame())
    assert lines[:11] == [
        "stack teleop: vehicle v1 (real time)",
        "vehicle: Position, armed, failsafe: no",
        "altitude 5.0 m above home, climb +0.5 m/s",
        "position N 0.0 E 0.0 m (local), speed 5.0 m/s",
        "battery 15.8 V, 92 %, warning none",
        "sticks (keyboard, stick limit 50 %), sent at 50 Hz",
        "  roll     [----------|###-------] +0.30",
        "  pitch    [-----#####|----------] -0.50",
        "  yaw      [----------|----------] +0.00",
        "  throttle [----------|----------] +0.00",
        "last command #2: mode Position: accepted",
    ]
    assert lines[11:] == ["log: Mode: Position", "", *keyboard_keys()]
    assert all(len(line) < 80 for line in keyboard_keys())


def test_no_home_no_vehicle_a_silent_vehicle_and_sticks_not_sent():
    f = frame(silent_s=5.2, sending=False)
    f.summary["position"]["altitude_above_home"] = math.nan
    lines = render(f)
    assert "nothing heard from the vehicle for 5 s (did the stack stop?)" in lines
    assert "altitude 5.0 m above the origin, climb +0.5 m/s" in lines
    assert "sticks (keyboard, stick limit 50 %), NOT sent: the commander's RC-loss failsafe acts" in lines
    lines = render(frame(summary={}, velocity=None, subscribed=False, answer="", said=[]))
    assert lines[:3] == [
        "stack teleop: vehicle v1 (real time)",
        "vehicle: no vehicle_status (is a commander running?)",
        "sticks (keyboard, stick limit 50 %), sent, but nothing subscribes to them (is the commander running?)",
    ]


def test_in_the_rotors_mode_what_the_sticks_command():
    sticks = Sticks(1.0, 0.5, -1.0, 0.0)
    lines = render(frame(sticks=sticks, rotors=JoyMapping().command(*sticks)))
    assert "RotorS: roll +10.0°, pitch -5.0° (nose up +), yaw rate -45°/s, thrust 15.0 N" in lines
    lines = render(frame(sticks=Sticks(), rotors=JoyMapping().command(*Sticks())))
    assert "RotorS: roll +0.0°, pitch +0.0° (nose up +), yaw rate +0°/s, thrust 0.0 N" in lines


def test_the_gamepads_mapping_fits_a_terminal():
    keys = gamepad_keys(load_mapping(DEFAULT_MAPPING))
    assert keys[1:] == [
        "axes: roll 3, pitch 4 inverted, yaw 0, throttle 1 inverted",
        "buttons: 0 Position, 1 Altitude, 2 Stabilized, 3 RotorS, 4 Acro, 5 Land,",
        "  6 disarm, 7 arm",
        "keys: m arm, x disarm, q quit",
        "modes 1 Stabilized 2 Acro 3 Altitude 4 Position 5 RotorS 6 Hold 7 Land 8 Return",
    ]
    assert all(len(line) < 80 for line in keys[1:])
