"""Messages as JSON for `stack topic`: every topic in the registry from a generated example, nested structs
(a mission's items) by field name, and field paths for `echo --field`."""

import json
import math
import re

import msgspec
import pytest

from stack.cli.message_json import as_dict, parse_field_paths, parse_message, pick
from stack.msg.registry import TOPICS


def example(topic: str) -> str:
    """A JSON example for the topic: its defaults, with one item in each list of structs."""
    data = as_dict(TOPICS[topic].type())
    for name, f in zip(TOPICS[topic].type.__struct_fields__, msgspec.structs.fields(TOPICS[topic].type), strict=True):
        args = getattr(f.type, "__args__", ())
        if isinstance(data[name], list) and args and isinstance(args[0], type) and issubclass(args[0], msgspec.Struct):
            data[name] = [as_dict(args[0]())]
    return json.dumps(data)


def same(a: object, b: object) -> bool:
    """Equal, NaN matching NaN."""
    return msgspec.json.encode(a) == msgspec.json.encode(b)


@pytest.mark.parametrize("topic", sorted(TOPICS))
def test_every_topic_takes_its_generated_example(topic):
    text = example(topic)
    msg = parse_message(topic, text)
    assert type(msg) is TOPICS[topic].type
    assert same(as_dict(msg), json.loads(text))
    # It goes on the wire and back as the real type.
    assert same(msgspec.msgpack.decode(msgspec.msgpack.encode(msg), type=TOPICS[topic].type), msg)


def test_a_mission_with_items_by_field_name():
    items = '[{"command": 22, "down": -5}, {"north": -10.5, "east": 3}]'
    msg = parse_message("mission", f'{{"mission_id": 7, "items": {items}, "source": "x"}}')
    takeoff, waypoint = msg.items
    assert (msg.mission_id, takeoff.command, takeoff.down, waypoint.command, waypoint.north) == (7, 22, -5.0, 16, -10.5)
    assert math.isnan(takeoff.north) and msg.source == "x"


def test_a_message_larger_than_the_bus_carries_is_one_line():
    items = json.dumps([{"north": float(i)} for i in range(1000)])
    with pytest.raises(ValueError) as e:
        parse_message("mission", f'{{"items": {items}}}')
    assert re.fullmatch(r"Mission: \d+ bytes, more than the 48000 one message on the bus may have", str(e.value))


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ('{"items": [{"comand": 16}]}', "Mission: Object contains unknown field `comand` - at `items[0]`"),
        ('{"items": [[16, 1]]}', "Mission: Expected `object`, got `array` - at `items[0]`"),
        ('{"items": 5}', "Mission: Expected `array`, got `int` - at `items`"),
        ('{"items": [{"north": "far"}]}', "Mission: Expected `float`, got `str` - at `items[0].north`"),
        ("-1", "expected a JSON object of field values, e.g. '{\"roll\": 0.1}'"),
    ],
)
def test_bad_nested_input_is_one_line(text, why):
    with pytest.raises(ValueError) as e:
        parse_message("mission", text)
    assert str(e.value) == why


def test_field_paths_reach_into_nested_fields_and_lists():
    data = as_dict(parse_message("mission", '{"mission_id": 3, "items": [{"north": -5}]}'))
    assert parse_field_paths(["a,b", " c ", "d.0"]) == ["a", "b", "c", "d.0"]
    assert pick(data, "mission_id") == 3 and pick(data, "items.0.north") == -5.0
    assert pick(as_dict(TOPICS["vehicle_attitude"].type()), "q.0") == 1.0
    for path, why in (
        ("items.1.north", "'items.1': index must be 0…0"),
        ("items.x", "'items.x': index must be 0…0"),
        ("items.0.up", "no field 'items.0.up' (fields: command, frame, north,"),
        ("mission_id.x", "'mission_id.x': mission_id has no fields"),
    ):
        with pytest.raises(KeyError) as e:
            pick(data, path)
        assert e.value.args[0].startswith(why)
