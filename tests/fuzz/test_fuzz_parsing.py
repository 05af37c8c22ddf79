"""Fuzz what comes from outside as text or MAVLink: mission files and ground-station commands. A bad one is
refused with a reason (MissionError, a Refusal); nothing else is raised."""

from __future__ import annotations

import json

from hypothesis import given
from hypothesis import strategies as st
from pymavlink.dialects.v20 import common as mavlink2

from stack.commander.state_machine import SUPPORTED_COMMANDS
from stack.mavlink.commands import Refusal, from_command_int, from_command_long, from_set_mode
from stack.mission.items import MissionError
from stack.mission.plan import parse_plan
from stack.mission.waypoints import parse_waypoint_list, parse_wpl
from stack.msg.system import VehicleCommand
from tests.fuzz.strategies import FUZZ, nasty_float

SUPPORTED = SUPPORTED_COMMANDS
OWN = (1, 1)
json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), nasty_float, st.integers(), st.text(max_size=8)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12,
)
item = st.fixed_dictionaries(
    {"type": st.sampled_from(["SimpleItem", "ComplexItem", 3]), "command": st.one_of(st.integers(), nasty_float),
     "frame": st.integers(-1, 12), "params": st.lists(st.one_of(nasty_float, st.none(), st.text(max_size=3)),
                                                      max_size=8),
     "autoContinue": st.booleans(), "doJumpId": st.integers()},
)
plans = st.fixed_dictionaries(
    {"fileType": st.just("Plan"),
     "mission": st.fixed_dictionaries({"items": st.lists(st.one_of(item, json_values), max_size=4),
                                       "plannedHomePosition": st.one_of(st.lists(nasty_float, max_size=4),
                                                                        json_values)})},
)


def _parses_or_refuses(parse, text: str) -> None:
    try:
        parse(text)
    except MissionError as e:
        assert str(e)


@FUZZ
@given(doc=st.one_of(plans, json_values))
def test_any_plan_parses_or_is_refused_with_a_reason(doc):
    _parses_or_refuses(parse_plan, json.dumps(doc))


line = st.lists(st.one_of(st.sampled_from(["takeoff", "waypoint", "land", "rtl", "loiter", "speed", "yaw", "#"]),
                          st.sampled_from(["nan", "inf", "-inf", "1e999", "1e9", "-0", "x"]),
                          st.floats(allow_nan=True).map(repr), st.text(max_size=5)), max_size=7).map(" ".join)


@FUZZ
@given(lines=st.lists(line, max_size=5), header=st.booleans())
def test_any_waypoint_file_parses_or_is_refused_with_a_reason(lines, header):
    text = "\n".join(lines)
    _parses_or_refuses(parse_waypoint_list, text)
    _parses_or_refuses(parse_wpl, ("QGC WPL 110\n" if header else "") + text.replace(" ", "\t"))


commands = st.one_of(st.sampled_from(sorted(SUPPORTED)), st.integers(0, 65535))
params7 = st.lists(nasty_float, min_size=7, max_size=7)


@FUZZ
@given(command=commands, params=params7, frame=st.integers(0, 21), x=st.integers(-(2**31), 2**31 - 1),
       y=st.integers(-(2**31), 2**31 - 1), home_alt=nasty_float)
def test_any_mavlink_command_becomes_a_vehicle_command_or_a_refusal(command, params, frame, x, y, home_alt):
    long = mavlink2.MAVLink_command_long_message(1, 1, command, 0, *params)
    out = from_command_long(long, (255, 190), OWN, SUPPORTED)
    assert isinstance(out, VehicleCommand | Refusal)
    short = mavlink2.MAVLink_command_int_message(1, 1, frame, command, 0, 0, *params[:4], x, y, params[6])
    out = from_command_int(short, (255, 190), OWN, SUPPORTED, home_alt)
    assert isinstance(out, VehicleCommand | Refusal)


@FUZZ
@given(base=st.integers(0, 255), custom=st.integers(0, 2**32 - 1))
def test_any_set_mode_becomes_a_do_set_mode(base, custom):
    cmd = from_set_mode(mavlink2.MAVLink_set_mode_message(1, base, custom), (255, 190), OWN)
    assert cmd.command == VehicleCommand.VEHICLE_CMD_DO_SET_MODE
