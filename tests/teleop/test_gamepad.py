"""A gamepad by its mapping file: axes with inversion and dead zone, buttons that act when pressed (not when the
device reports its state on opening), the shipped Xbox-layout mapping, and bad mapping files refused naming the
file, the key and the problem."""

from pathlib import Path

import pytest

from stack.teleop.gamepad import DEFAULT_MAPPING, AxisMap, Gamepad, MappingError, load_mapping
from stack.teleop.joystick import JS_EVENT_AXIS, JS_EVENT_BUTTON, JS_EVENT_INIT, JsEvent
from stack.teleop.sticks import Sticks

INIT = JS_EVENT_INIT


def axis(number: int, value: int, init: bool = False) -> JsEvent:
    return JsEvent(0, value, JS_EVENT_AXIS | (INIT if init else 0), number)


def button(number: int, value: int, init: bool = False) -> JsEvent:
    return JsEvent(0, value, JS_EVENT_BUTTON | (INIT if init else 0), number)


def test_an_axis_reads_with_inversion_and_joy_nodes_dead_zone():
    m = AxisMap(0, invert=False, deadzone=0.1)
    assert m.read(32767) == 1.0
    assert m.read(-32768) == -1.0
    assert m.read(3000) == 0.0  # within 0.1 of centre
    assert m.read(round(0.55 * 32767)) == pytest.approx(0.5, abs=1e-4)
    assert AxisMap(0, invert=True).read(-32767) == 1.0


def test_the_shipped_mapping_flies_an_xbox_pad_mode_2():
    pad = Gamepad(load_mapping(DEFAULT_MAPPING))
    assert pad.sticks() == Sticks(0.0, 0.0, 0.0, 0.0)
    pad.take(axis(1, -32767))  # left stick forward: throttle up
    pad.take(axis(0, 32767))  # left stick right: yaw clockwise
    pad.take(axis(4, -32767))  # right stick forward: pitch forward
    pad.take(axis(3, -32767))  # right stick left: roll left
    assert pad.sticks() == Sticks(-1.0, 1.0, 1.0, 1.0)
    assert pad.take(button(7, 1)) == "arm"  # Start
    assert pad.take(button(6, 1)) == "disarm"  # Back
    assert pad.take(button(0, 1)) == "posctl"  # A
    assert pad.take(button(3, 1)) == "rotors"  # Y


def test_a_button_acts_once_when_pressed_and_not_for_its_state_on_opening():
    pad = Gamepad(load_mapping(DEFAULT_MAPPING))
    assert pad.take(button(7, 1, init=True)) is None  # held while the device was opened
    assert pad.take(button(7, 1)) is None  # still held
    assert pad.take(button(7, 0)) is None
    assert pad.take(button(7, 1)) == "arm"
    assert pad.take(button(7, 1)) is None
    assert pad.take(button(9, 1)) is None  # a button without an action
    assert pad.take(axis(1, -32767, init=True)) is None
    assert pad.sticks().throttle == 1.0  # the state on opening sets the sticks


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "pad.toml"
    path.write_text(text)
    return path


AXES = """
[axes]
roll = { axis = 0 }
pitch = { axis = 1, invert = true, deadzone = 0.2 }
yaw = { axis = 2 }
throttle = { axis = 3, invert = true, deadzone = 0 }
"""


def test_a_mapping_file_of_ones_own(tmp_path):
    m = load_mapping(write(tmp_path, AXES + '[buttons]\narm = 0\n"auto:loiter" = 1\nhold = 2\n'))
    assert m.axes["pitch"] == AxisMap(1, True, 0.2)
    assert m.axes["roll"] == AxisMap(0, False, 0.05)
    assert m.buttons == {0: "arm", 1: "auto:loiter", 2: "hold"}
    assert load_mapping(write(tmp_path, AXES)).buttons == {}


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("[axes\n", "TOML syntax error"),
        ("axes = 3\n", "axes: expected a table"),
        ("[buttons]\narm = 0\n", "axes: missing"),
        (AXES + "[extra]\n", "extra: unknown key (a mapping has axes and buttons)"),
        (AXES.replace("yaw = { axis = 2 }", ""), "axes.yaw: missing: every stick needs an axis"),
        (AXES + "flaps = { axis = 5 }\n", "axes.flaps: not a stick (sticks: roll, pitch, yaw, throttle)"),
        (AXES.replace("axis = 2", "axis = 256"), "axes.yaw.axis: expected an axis number 0..255, got 256"),
        (AXES.replace("axis = 2", 'axis = "2"'), "axes.yaw.axis: expected an axis number 0..255, got '2'"),
        (AXES.replace("axis = 2", "axis = true"), "axes.yaw.axis: expected an axis number 0..255, got True"),
        (AXES.replace("{ axis = 2 }", "{ }"), "axes.yaw.axis: missing"),
        (AXES.replace("{ axis = 2 }", "2"), "axes.yaw: expected a table"),
        (AXES.replace("axis = 2", "axis = 0"), "axes.yaw: axis 0 is already axes.roll's"),
        (AXES.replace("deadzone = 0.2", "deadzone = 1.0"), "axes.pitch.deadzone: expected a number from 0 up to"),
        (AXES.replace("invert = true, deadzone = 0.2", 'invert = "yes"'), "axes.pitch.invert: expected true or false"),
        (AXES.replace("{ axis = 2 }", "{ axis = 2, scale = 2 }"), "axes.yaw.scale: unknown key (an axis has"),
        (AXES + "[buttons]\nfly = 1\n", "buttons.fly: not an action: expected arm, disarm or a mode name; unknown"),
        (AXES + "[buttons]\narm = -1\n", "buttons.arm: expected a button number 0..255, got -1"),
        (AXES + "[buttons]\narm = 1\ndisarm = 1\n", "buttons.disarm: button 1 is already buttons.arm's"),
        ("buttons = [1]\n" + AXES, "buttons: expected a table"),
    ],
)
def test_a_bad_mapping_is_refused_naming_the_file_the_key_and_the_problem(tmp_path, text, problem):
    path = write(tmp_path, text)
    with pytest.raises(MappingError) as e:
        load_mapping(path)
    assert str(e.value).startswith(f"{path}: {problem}")


def test_a_mapping_file_that_cannot_be_read(tmp_path):
    with pytest.raises(MappingError, match=r"nope\.toml: cannot read it: No such file or directory"):
        load_mapping(tmp_path / "nope.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe")
    with pytest.raises(MappingError, match="TOML syntax error"):
        load_mapping(tmp_path / "bin.toml")
