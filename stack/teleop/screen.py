"""The screen of ``stack teleop``, as lines of text: the vehicle's state, the sticks, and the keys."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.cli.vehicle_summary import lines as summary_lines
from stack.commander.modes import MODES, nav_state_from_name
from stack.teleop.actions import ARM, DISARM
from stack.teleop.gamepad import STICKS, Mapping
from stack.teleop.keyboard import ACTION_KEYS
from stack.teleop.sticks import Sticks

BAR_HALF = 10
WIDTH = 79
"""The widest line of the key help (a terminal of 80 columns)."""
SILENT_S = 2.0
"""Seconds without a word from the vehicle after which the screen says so."""


@dataclass
class Frame:
    vehicle: str
    clock: str
    """How the stack runs: "real time", or lockstep and its pace (with a warning unless at real speed)."""
    summary: dict[str, Any]
    """:func:`stack.cli.vehicle_summary.summary` of the vehicle's latest messages."""
    velocity: tuple[float, float, float] | None
    """North, east, down [m/s]."""
    sticks: Sticks
    source: str
    """Where the sticks come from, e.g. "keyboard, stick limit 50 %"."""
    sending: bool
    subscribed: bool
    """Whether anything subscribes to the sticks."""
    rate_hz: float
    silent_s: float
    """Seconds since the vehicle was last heard from."""
    keys: list[str]
    answer: str = ""
    """The outcome of the last command sent."""
    commands: int = 0
    """Commands asked for: the last one's number."""
    said: list[str] = field(default_factory=list)
    """The vehicle's latest messages, oldest first."""
    rotors: RollPitchYawrateThrust | None = None
    """What the sticks command in the RotorS mode (None in other modes)."""


def render(f: Frame) -> list[str]:
    s = f.summary
    out = [f"stack teleop: vehicle {f.vehicle} ({f.clock})", summary_lines(s)[0]]
    if f.silent_s > SILENT_S:
        out.append(f"nothing heard from the vehicle for {f.silent_s:.0f} s (did the stack stop?)")
    if (p := s.get("position")) is not None:
        above = p["altitude_above_home"]
        if math.isfinite(above):
            altitude = f"altitude {_fixed(above)} m above home"
        else:
            altitude = f"altitude {_fixed(-p['down'])} m above the origin"
        position = f"position N {_fixed(p['north'])} E {_fixed(p['east'])} m (local)"
        if f.velocity is not None:
            altitude += f", climb {_fixed(-f.velocity[2], '+')} m/s"
            position += f", speed {math.hypot(*f.velocity):.1f} m/s"
        out += [altitude, position]
    if (b := s.get("battery")) is not None:
        remaining = f", {b['remaining'] * 100:.0f} %" if b["remaining"] >= 0 else ""
        out.append(f"battery {b['voltage_v']:.1f} V{remaining}, warning {b['warning']}")
    if not f.sending:
        state = "NOT sent: the commander's RC-loss failsafe acts"
    elif not f.subscribed:
        state = "sent, but nothing subscribes to them (is the commander running?)"
    else:
        state = f"sent at {f.rate_hz:.0f} Hz"
    out.append(f"sticks ({f.source}), {state}")
    out.extend(f"  {name:<8} {_bar(value)} {value:+.2f}" for name, value in zip(STICKS, f.sticks, strict=True))
    if (r := f.rotors) is not None:
        out.append(
            f"RotorS: roll {_fixed(math.degrees(r.roll), '+')}°, pitch {_fixed(math.degrees(r.pitch), '+')}° "
            f"(nose up +), yaw rate {_fixed(math.degrees(r.yaw_rate), '+', 0)}°/s, thrust {r.thrust:.1f} N"
        )
    if f.answer:
        out.append(f"last command #{f.commands}: {f.answer}")
    out.extend(f"log: {text}" for text in f.said)
    out.append("")
    out.extend(f.keys)
    return out


def _fixed(value: float, sign: str = "", digits: int = 1) -> str:
    """``value`` with ``digits`` decimals, without the minus of a value that rounds to zero."""
    text = f"{value:{sign}.{digits}f}"
    return f"{0.0:{sign}.{digits}f}" if float(text) == 0.0 else text


def _bar(value: float) -> str:
    """A stick as ``[----|##--]``: filled from the centre towards its deflection."""
    n = round(min(1.0, abs(value)) * BAR_HALF)
    left = "-" * (BAR_HALF - n) + "#" * n if value < 0 else "-" * BAR_HALF
    right = "#" * n + "-" * (BAR_HALF - n) if value > 0 else "-" * BAR_HALF
    return f"[{left}|{right}]"


def _label(action: str) -> str:
    if action in (ARM, DISARM):
        return action
    return MODES[nav_state_from_name(action)].name


def _commands() -> list[str]:
    named = {action: key for key, action in ACTION_KEYS.items()}
    modes = " ".join(f"{key} {_label(action)}" for key, action in ACTION_KEYS.items() if action not in (ARM, DISARM))
    return [f"{named[ARM]} arm, {named[DISARM]} disarm, q quit", f"modes {modes}"]


def keyboard_keys() -> list[str]:
    commands, modes = _commands()
    return [
        "keys: arrows pitch/roll, a/d yaw, w/s throttle (stays), space centre,",
        f"      [ ] stick limit, {commands}",
        modes,
    ]


def gamepad_keys(mapping: Mapping) -> list[str]:
    axes = [f"{name} {m.axis}{' inverted' if m.invert else ''}" for name, m in mapping.axes.items()]
    buttons = [f"{number} {_label(action)}" for number, action in sorted(mapping.buttons.items())]
    commands, modes = _commands()
    return [
        f"gamepad mapping {mapping.source}",
        *_wrap("axes: ", axes),
        *_wrap("buttons: ", buttons or ["none"]),
        f"keys: {commands}",
        modes,
    ]


def _wrap(head: str, items: list[str]) -> list[str]:
    """``head`` and the items, comma-separated, in lines of at most WIDTH that break between items."""
    lines = [head + items[0]]
    for item in items[1:]:
        if len(lines[-1]) + len(item) + 2 > WIDTH:
            lines[-1] += ","
            lines.append("  " + item)
        else:
            lines[-1] += ", " + item
    return lines
