"""The keyboard as a pair of sticks, for a plain terminal that reports key presses but never releases.

Arrows move the right stick (pitch, roll), a/d the yaw stick, w/s the throttle, as RotorS' ``key_joystick.py``
lays them out. A held key reaches the program as one press, then, after the system's auto-repeat delay (250 ms
on the Linux console, 500–660 ms under X11 and Wayland desktops), as a press every 30–40 ms. So a stick holds
after a first press for FIRST_HOLD_S, longer than any usual delay, and, once the presses repeat, for
REPEAT_HOLD_S after the last one: the time a released key takes to be noticed. Then it springs back to centre at
DECAY_PER_S, as teleop_twist_keyboard's ``key_timeout`` stops a robot. The first press deflects the stick by
TAP of the stick limit, each repeat STEP more, up to the limit ([ and ] change it). The throttle stays where it
is put: each press moves it by THROTTLE_STEP. A terminal repeats only the last key pressed: a stick held with
another key pressed after it springs back.
"""

from __future__ import annotations

from stack.teleop.actions import ARM, DISARM
from stack.teleop.sticks import Sticks

FIRST_HOLD_S = 0.75
REPEAT_HOLD_S = 0.15
DECAY_PER_S = 4.0
TAP = 0.5
STEP = 0.1
THROTTLE_STEP = 0.05
LIMITS = (0.25, 0.5, 0.75, 1.0)
DEFAULT_LIMIT = 0.5
QUIT = "quit"

STICK_KEYS: dict[str, tuple[str, int]] = {
    "up": ("pitch", 1),
    "down": ("pitch", -1),
    "right": ("roll", 1),
    "left": ("roll", -1),
    "d": ("yaw", 1),
    "a": ("yaw", -1),
}
THROTTLE_KEYS = {"w": 1, "s": -1}
LIMIT_KEYS = {"]": 1, "[": -1}
CENTRE_KEY = " "
ACTION_KEYS: dict[str, str] = {
    "m": ARM,
    "x": DISARM,
    "1": "stabilized",
    "2": "acro",
    "3": "altctl",
    "4": "posctl",
    "5": "rotors",
    "6": "auto:loiter",
    "7": "auto:land",
    "8": "auto:rtl",
}
QUIT_KEYS = frozenset({"q", "\x03", "\x04"})
"""q, Ctrl-C (a byte when the terminal does not turn it into SIGINT) and Ctrl-D."""


class _Axis:
    """A spring-centred stick: deflected ``level`` towards ``direction`` at the last press, ``last``."""

    __slots__ = ("direction", "last", "level", "repeating")

    def __init__(self) -> None:
        self.direction = 1
        self.level = 0.0
        self.last = float("-inf")
        self.repeating = False

    def _hold_s(self) -> float:
        return REPEAT_HOLD_S if self.repeating else FIRST_HOLD_S

    def value(self, now: float) -> float:
        released_for = now - self.last - self._hold_s()
        level = self.level if released_for <= 0.0 else max(0.0, self.level - DECAY_PER_S * released_for)
        return self.direction * level

    def press(self, direction: int, now: float, limit: float) -> None:
        held = direction == self.direction and now - self.last <= self._hold_s()
        if held:
            self.level = min(limit, self.level + STEP * limit)
        else:
            springing_back = self.value(now) * direction
            self.level = max(TAP * limit, springing_back)
        self.repeating = held
        self.direction = direction
        self.last = now


class Keyboard:
    """Keys in, sticks and actions out; ``now`` is any monotonic clock in seconds."""

    def __init__(self) -> None:
        self._axes = {name: _Axis() for name in ("roll", "pitch", "yaw")}
        self.throttle = -1.0
        self.limit = DEFAULT_LIMIT

    def key(self, key: str, now: float) -> str | None:
        """Take a key: move a stick, or return what it asks (an action of :mod:`.actions`, or QUIT)."""
        key = key.lower()  # with Caps Lock on, W still climbs
        if key in QUIT_KEYS:
            return QUIT
        if key in ACTION_KEYS:
            return ACTION_KEYS[key]
        if key in STICK_KEYS:
            axis, direction = STICK_KEYS[key]
            self._axes[axis].press(direction, now, self.limit)
        elif key in THROTTLE_KEYS:
            self.throttle = min(1.0, max(-1.0, round(self.throttle + THROTTLE_KEYS[key] * THROTTLE_STEP, 2)))
        elif key in LIMIT_KEYS:
            i = LIMITS.index(self.limit) + LIMIT_KEYS[key]
            self.limit = LIMITS[min(len(LIMITS) - 1, max(0, i))]
            for axis in self._axes.values():
                axis.level = min(axis.level, self.limit)
        elif key == CENTRE_KEY:
            for axis in self._axes.values():
                axis.level = 0.0
            self.throttle = 0.0
        return None

    def sticks(self, now: float) -> Sticks:
        a = self._axes
        return Sticks(a["roll"].value(now), a["pitch"].value(now), a["yaw"].value(now), self.throttle)
