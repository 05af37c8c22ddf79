"""QGroundControl's parameter files (``.params``), as QGC saves and loads them for a PX4 vehicle.

``#`` lines are comments (QGC writes a header naming the columns); every other non-blank line is one
parameter, tab-separated::

    # Vehicle-Id  Component-Id  Name  Value  Type
    1	1	MC_ROLLRATE_P	0.15	9

Type is the MAV_PARAM_TYPE: PX4 uses 6 (INT32) and 9 (REAL32); QGC may write the other integer types (1-8)
for other autopilots, which read as integers here. Floats are written with ``repr`` so that a saved value
loads back exactly.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import NamedTuple

from stack.params.param import MAV_PARAM_TYPE_REAL32

MAV_PARAM_TYPE_NAMES = {
    1: "UINT8",
    2: "INT8",
    3: "UINT16",
    4: "INT16",
    5: "UINT32",
    6: "INT32",
    7: "UINT64",
    8: "INT64",
    9: "REAL32",
    10: "REAL64",
}
"""MAVLink's MAV_PARAM_TYPE enum."""

_INTEGER_TYPES = frozenset(range(1, 9))
_NAME = re.compile(r"[A-Za-z0-9_]{1,16}")
"""MAVLink parameter ids are at most 16 characters (PARAM_VALUE.param_id)."""


class Entry(NamedTuple):
    """One parameter line: the name, the value as its type says, the MAV_PARAM_TYPE, and the vehicle's MAVLink
    system id (the Vehicle-Id column)."""

    line: int
    name: str
    value: int | float
    mav_type: int
    system_id: int = 1


def format_file(
    params: Iterable[tuple[str, bool | int | float, int]], vehicle: str, system_id: int = 1, component_id: int = 1
) -> str:
    """The file for ``(name, value, mav_type)`` triples, with QGC's header."""
    lines = [
        f"# Onboard parameters for {vehicle}",
        "#",
        "# Stack parameters",
        "#",
        "# Vehicle-Id Component-Id Name Value Type",
    ]
    for name, value, mav_type in params:
        text = repr(float(value)) if mav_type == MAV_PARAM_TYPE_REAL32 else str(int(value))
        lines.append(f"{system_id}\t{component_id}\t{name}\t{text}\t{mav_type}")
    return "\n".join(lines) + "\n"


def parse_file(text: str) -> tuple[list[Entry], list[str]]:
    """(the parameter lines, the problems: one message per line that is not one, naming its line number)."""
    entries: list[Entry] = []
    problems: list[str] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        try:
            entries.append(_parse_line(number, line))
        except ValueError as e:
            problems.append(f"line {number}: {e}")
    return entries, problems


def _parse_line(number: int, line: str) -> Entry:
    fields = line.split("\t") if "\t" in line else line.split()
    if len(fields) != 5:
        raise ValueError(f"expected 5 tab-separated fields (vehicle, component, name, value, type), got {len(fields)}")
    vehicle_id, component_id, name, value, type_text = (f.strip() for f in fields)
    if not (vehicle_id.isdigit() and component_id.isdigit()):
        raise ValueError(f"vehicle and component ids must be numbers, got {vehicle_id!r} and {component_id!r}")
    if not _NAME.fullmatch(name):
        raise ValueError(f"{name!r} is not a parameter name")
    try:
        mav_type = int(type_text)
    except ValueError:
        raise ValueError(f"{name}: type {type_text!r} is not a MAV_PARAM_TYPE number") from None
    if mav_type not in MAV_PARAM_TYPE_NAMES:
        raise ValueError(f"{name}: type {mav_type} is not a MAV_PARAM_TYPE")
    try:
        number_value: int | float = int(value) if mav_type in _INTEGER_TYPES else float(value)
    except ValueError:
        kind = "an integer" if mav_type in _INTEGER_TYPES else "a number"
        raise ValueError(f"{name}: value {value!r} is not {kind} ({MAV_PARAM_TYPE_NAMES[mav_type]})") from None
    return Entry(number, name, number_value, mav_type, int(vehicle_id))


def other_vehicle(entries: Iterable[Entry], system_id: int) -> str | None:
    """Why the file is not this vehicle's (MAVLink system ``system_id``), or None. As QGroundControl refuses a file
    saved from another system id (``ParameterManager::readParametersFromStream``), before setting anything: in a
    swarm, another vehicle's file would also set this one's MAV_SYS_ID to the other's."""
    others = sorted({e.system_id for e in entries} - {system_id})
    if not others:
        return None
    saved = ", ".join(str(i) for i in others)
    return f"the parameters were saved from system id {saved}, but this vehicle's is {system_id} (MAV_SYS_ID)"


def type_name(mav_type: int) -> str:
    return MAV_PARAM_TYPE_NAMES.get(mav_type, str(mav_type))
