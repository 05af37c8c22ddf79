"""A gamepad's axes and buttons as sticks and actions, by a mapping file.

A mapping is TOML: each stick's axis number on the device, with ``invert`` and ``deadzone`` optional, and the
button of each action (arm, disarm, or a mode as ``stack cmd mode`` names it)::

    [axes]
    roll = { axis = 3 }
    pitch = { axis = 4, invert = true, deadzone = 0.1 }
    yaw = { axis = 0 }
    throttle = { axis = 1, invert = true }

    [buttons]
    arm = 7
    posctl = 0

An axis reads value/32767, + right and down as the kernel reports it (so a stick pushed forward reads −1: pitch
and throttle want ``invert``), with ROS joy_node's dead zone: within ``deadzone`` of centre 0, beyond it
(|v| − deadzone)/(1 − deadzone). A button acts when pressed; the state the device reports on opening
(JS_EVENT_INIT) sets the sticks but presses nothing, so a button held then arms nothing.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from stack.teleop import actions
from stack.teleop.joystick import AXIS_MAX, JS_EVENT_AXIS, JsEvent
from stack.teleop.sticks import Sticks

DEFAULT_MAPPING = Path(__file__).with_name("xbox.toml")
DEFAULT_DEADZONE = 0.05
"""joy_node's default."""
STICKS = Sticks._fields
NUMBERS = range(256)
"""A js_event's axis or button number is a byte."""


class MappingError(ValueError):
    """A mapping file was refused; the message names the file, the key and the problem."""


Error = Callable[[str, str], MappingError]
"""(key, problem) → the error naming the file."""


class AxisMap(NamedTuple):
    axis: int
    invert: bool = False
    deadzone: float = DEFAULT_DEADZONE

    def read(self, raw: int) -> float:
        v = max(-1.0, min(1.0, raw / AXIS_MAX))
        v = -v if self.invert else v
        if abs(v) <= self.deadzone:
            return 0.0
        return math.copysign((abs(v) - self.deadzone) / (1.0 - self.deadzone), v)


@dataclass(frozen=True)
class Mapping:
    source: str
    axes: dict[str, AxisMap]
    buttons: dict[int, str]
    """Button number → action."""


def load_mapping(path: Path) -> Mapping:
    try:
        doc = tomllib.loads(path.read_text())
    except OSError as e:
        raise MappingError(f"{path}: cannot read it: {e.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise MappingError(f"{path}: TOML syntax error: {e}") from None

    def error(key: str, problem: str) -> MappingError:
        return MappingError(f"{path}: {key}: {problem}")

    for key in doc:
        if key not in ("axes", "buttons"):
            raise error(key, "unknown key (a mapping has axes and buttons)")
    axes_doc = _table(doc.get("axes"), "axes", error)
    axes: dict[str, AxisMap] = {}
    for name, spec in axes_doc.items():
        if name not in STICKS:
            raise error(f"axes.{name}", f"not a stick (sticks: {', '.join(STICKS)})")
        axes[name] = _axis(_table(spec, f"axes.{name}", error), f"axes.{name}", error)
    for name in STICKS:
        if name not in axes:
            raise error(f"axes.{name}", "missing: every stick needs an axis")
    for name, m in axes.items():
        other = next((o for o, n in axes.items() if n.axis == m.axis and o < name), None)
        if other is not None:
            raise error(f"axes.{name}", f"axis {m.axis} is already axes.{other}'s")
    buttons: dict[int, str] = {}
    for action, number in _table(doc.get("buttons", {}), "buttons", error).items():
        try:
            actions.check(action)
        except ValueError as e:
            raise error(f"buttons.{action}", f"not an action: expected arm, disarm or a mode name; {e}") from None
        number = _number(number, f"buttons.{action}", "a button", error)
        if number in buttons:
            raise error(f"buttons.{action}", f"button {number} is already buttons.{buttons[number]}'s")
        buttons[number] = action
    return Mapping(str(path), axes, buttons)


def _table(value: Any, key: str, error: Error) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise error(key, "expected a table" if value is not None else "missing")
    return value


def _number(value: Any, key: str, what: str, error: Error) -> int:
    if type(value) is not int or value not in NUMBERS:
        raise error(key, f"expected {what} number 0..255, got {value!r}")
    return value


def _axis(spec: dict[str, Any], key: str, error: Error) -> AxisMap:
    for k in spec:
        if k not in AxisMap._fields:
            raise error(f"{key}.{k}", f"unknown key (an axis has {', '.join(AxisMap._fields)})")
    if "axis" not in spec:
        raise error(f"{key}.axis", "missing")
    invert = spec.get("invert", False)
    if not isinstance(invert, bool):
        raise error(f"{key}.invert", f"expected true or false, got {invert!r}")
    deadzone = spec.get("deadzone", DEFAULT_DEADZONE)
    if type(deadzone) not in (int, float) or not 0.0 <= deadzone < 1.0:
        raise error(f"{key}.deadzone", f"expected a number from 0 up to (not including) 1, got {deadzone!r}")
    return AxisMap(_number(spec["axis"], f"{key}.axis", "an axis", error), invert, float(deadzone))


class Gamepad:
    """The device's state from its events."""

    def __init__(self, mapping: Mapping) -> None:
        self.mapping = mapping
        self._axes: dict[int, int] = {}
        self._pressed: set[int] = set()

    def take(self, event: JsEvent) -> str | None:
        """Note an event; the action of a button just pressed, if it has one."""
        if event.kind == JS_EVENT_AXIS:
            self._axes[event.number] = event.value
            return None
        if not event.value:
            self._pressed.discard(event.number)
            return None
        pressed = event.number in self._pressed
        self._pressed.add(event.number)
        return None if pressed or event.init else self.mapping.buttons.get(event.number)

    def sticks(self) -> Sticks:
        axes = self.mapping.axes
        return Sticks(*(axes[stick].read(self._axes.get(axes[stick].axis, 0)) for stick in STICKS))
