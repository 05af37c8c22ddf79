"""Messages as JSON objects and back, exactly, with schemas Foxglove's JSON Schema reader accepts."""

import json
import math
import struct

import msgspec
import pytest

from stack.msg.base import Message
from stack.msg.registry import TOPICS
from stack.msg.sensors import SensorGyro
from stack.record.jsoncodec import JsonMessageCodec, UnsupportedType, codec_for, nonfinite_name, schema_decoder

NEG_NAN = math.copysign(math.nan, -1.0)
TYPES = sorted({t.type.__name__: t.type for t in TOPICS.values()}.items())


def float_bits(x: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def with_every_float(msg_type: type[Message], pick) -> Message:
    """A message whose float fields (and float array items) all hold pick(i)."""
    values = []
    for i, v in enumerate(msgspec.structs.astuple(msg_type())):
        if isinstance(v, float):
            values.append(pick(i))
        elif isinstance(v, tuple) and v and isinstance(v[0], float):
            values.append(tuple(pick(i + k) for k in range(len(v))))
        else:
            values.append(v)
    return msg_type(*values)


def strict_json(data: bytes) -> object:
    def refuse(token: str) -> None:
        raise AssertionError(f"non-JSON token {token}")

    return json.loads(data, parse_constant=refuse)


@pytest.mark.parametrize(("name", "msg_type"), TYPES)
def test_every_catalogue_type_round_trips_bit_exactly(name, msg_type):
    codec = codec_for(msg_type)
    specials = (math.nan, NEG_NAN, math.inf, -math.inf, -0.0, 1e-310, 0.1, -1.5e300)
    for msg in (msg_type(), with_every_float(msg_type, lambda i: specials[i % len(specials)])):
        data = codec.encode(msg)
        obj = strict_json(data)
        assert list(obj) == list(msg_type.__struct_fields__)
        back = codec.decode(data)
        assert type(back) is msg_type
        # msgpack bytes compare every float bit for bit, the sign of NaN included.
        assert msgspec.msgpack.encode(back) == msgspec.msgpack.encode(msg)


def test_non_finite_floats_are_named_strings():
    msg = SensorGyro(x=math.nan, y=math.inf, z=-math.inf, temperature=NEG_NAN, clip_counter=(1, 2, 3))
    obj = strict_json(codec_for(SensorGyro).encode(msg))
    assert (obj["x"], obj["y"], obj["z"], obj["temperature"]) == ("NaN", "Infinity", "-Infinity", "-NaN")
    assert obj["clip_counter"] == [1, 2, 3]
    assert [nonfinite_name(v) for v in (math.nan, NEG_NAN, math.inf, -math.inf)] == [
        "NaN",
        "-NaN",
        "Infinity",
        "-Infinity",
    ]
    back = codec_for(SensorGyro).decode(codec_for(SensorGyro).encode(msg))
    assert float_bits(back.temperature) == float_bits(NEG_NAN) != float_bits(math.nan)


def test_a_float_array_with_one_non_finite_item_keeps_the_others():
    from stack.msg.setpoints import TrajectorySetpoint

    msg = TrajectorySetpoint(position=(1.0, math.nan, 3.0), velocity=(1e308, 1e308, 1e308))
    obj = strict_json(codec_for(TrajectorySetpoint).encode(msg))
    assert obj["position"] == [1.0, "NaN", 3.0]
    assert obj["velocity"] == [1e308, 1e308, 1e308]  # their sum overflows; the values do not


@pytest.mark.parametrize(("name", "msg_type"), TYPES)
def test_schemas_use_only_what_foxglove_reads(name, msg_type):
    """Foxglove's parseJsonSchema: object at the top, one type name per field, arrays with typed items
    (scalars, or objects for nested structs, which it reads as nested message definitions)."""
    schema = json.loads(codec_for(msg_type).schema)
    assert schema["type"] == "object" and schema["title"] == name
    assert list(schema["properties"]) == list(msg_type.__struct_fields__)
    info = {f.name: f for f in msgspec.inspect.type_info(msg_type).fields}
    scalars = {"boolean", "string", "number", "integer"}
    for field, prop in schema["properties"].items():
        assert prop["type"] in (*scalars, "array", "object"), field
        if prop["type"] == "object":  # a nested struct: an object of scalars and arrays of scalars
            assert {p["type"] for p in prop["properties"].values()} <= {*scalars, "array"}
        if prop["type"] == "array":
            items = prop["items"]
            assert items["type"] in (*scalars, "object"), field
            if items["type"] == "object":  # a list of nested structs: each item an object of scalar fields
                assert {p["type"] for p in items["properties"].values()} <= scalars
        if isinstance(info[field].type, msgspec.inspect.FloatType):
            assert prop["type"] == "number"
    assert '"NaN"' in schema["description"]


def test_fixed_and_variable_arrays_in_the_schema():
    from stack.msg.simulation import SimGroundtruth

    props = json.loads(codec_for(SimGroundtruth).schema)["properties"]
    assert props["q"] == {"type": "array", "items": {"type": "number"}, "minItems": 4, "maxItems": 4}
    assert props["motors"] == {"type": "array", "items": {"type": "number"}}


def test_types_json_schema_readers_cannot_describe_are_refused():
    class Mixed(Message):
        pair: tuple[int, str] = (0, "")

    class Nested(Message):
        pairs: list[tuple[int, int]] = msgspec.field(default_factory=list)

    for bad in (Mixed, Nested):
        with pytest.raises(UnsupportedType, match=bad.__name__):
            JsonMessageCodec(bad)


def test_a_nested_struct_is_an_object_and_its_non_finite_floats_survive():
    from stack.msg.fixedwing import PositionSetpoint, PositionSetpointTriplet

    msg = PositionSetpointTriplet(current=PositionSetpoint(valid=True, x=1.0, loiter_radius=math.inf))
    codec = codec_for(PositionSetpointTriplet)
    obj = strict_json(codec.encode(msg))
    assert obj["current"]["x"] == 1.0 and obj["current"]["loiter_radius"] == "Infinity"
    assert obj["previous"]["x"] == "NaN"
    assert json.loads(codec.schema)["properties"]["current"]["title"] == "PositionSetpoint"
    assert msgspec.msgpack.encode(codec.decode(codec.encode(msg))) == msgspec.msgpack.encode(msg)
    by_schema = schema_decoder(codec.schema)(codec.encode(msg))
    assert by_schema["current"]["loiter_radius"] == math.inf and math.isnan(by_schema["previous"]["x"])


def test_decoding_refuses_a_string_that_is_not_a_non_finite_name():
    codec = codec_for(SensorGyro)
    data = codec.encode(SensorGyro()).replace(b'"temperature":"NaN"', b'"temperature":"warm"')
    with pytest.raises(msgspec.ValidationError, match="warm"):
        codec.decode(data)


def test_schema_decoder_reads_a_type_this_build_lacks():
    class Probe(Message):
        level: float = 0.0
        gains: tuple[float, float] = (0.0, 0.0)
        name: str = ""

    codec = JsonMessageCodec(Probe)
    data = codec.encode(Probe(timestamp=5, level=math.inf, gains=(1.0, NEG_NAN), name="NaN"))
    fields = schema_decoder(codec.schema)(data)
    assert list(fields) == ["timestamp", "level", "gains", "name"]
    assert fields["level"] == math.inf and fields["name"] == "NaN"  # a string field keeps its text
    assert fields["gains"][0] == 1.0 and float_bits(fields["gains"][1]) == float_bits(NEG_NAN)
