"""Messages as JSON objects keyed by field name, with a JSON Schema per type, losslessly.

On the bus a message is a msgpack array (its Struct is ``array_like``); in a recording it is a
JSON object, because that is what Foxglove and PlotJuggler decode (MCAP message encoding
``json``, schema encoding ``jsonschema``). JSON has no NaN or infinity, and the stack uses both
(NaN means "not controlled", infinity "no bound"), so non-finite floats are written as strings:

    "NaN", "-NaN" (a NaN with the sign bit set, what x86 arithmetic produces), "Infinity", "-Infinity"

Decoding turns them back, so a recorded message decodes to exactly the published one (NaN payload
bits other than the sign are not kept; Python never sets them).

The JSON Schema declares float fields as plain ``"type": "number"``: Foxglove's JSON Schema reader
accepts only a single type name per field (no ``anyOf``, no type lists) and fails the whole topic
otherwise. A plot then shows a gap where a value is non-finite, which is what NaN means anyway.
The convention is stated in each schema's description.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable
from typing import Annotated, Any

import msgspec

NONFINITE_NAMES = ("NaN", "-NaN", "Infinity", "-Infinity")
NONFINITE_VALUES: dict[str, float] = {
    "NaN": math.nan,
    "-NaN": math.copysign(math.nan, -1.0),
    "Infinity": math.inf,
    "-Infinity": -math.inf,
}
NONFINITE_RULE = (
    'Non-finite floats are written as the strings "NaN", "-NaN" (sign bit set), "Infinity" and "-Infinity".'
)

_inspect = msgspec.inspect
_SCALARS: dict[type, tuple[str, Any]] = {
    _inspect.IntType: ("integer", int),
    _inspect.FloatType: ("number", float),
    _inspect.BoolType: ("boolean", bool),
    _inspect.StrType: ("string", str),
}


class UnsupportedType(TypeError):
    """A message type with a field JSON Schema readers cannot describe (mixed or nested containers)."""


def nonfinite_name(value: float) -> str:
    """The JSON string standing for a non-finite float."""
    if value != value:
        return "-NaN" if math.copysign(1.0, value) < 0.0 else "NaN"
    return "Infinity" if value > 0.0 else "-Infinity"


def _scalar(t: _inspect.Type, where: str) -> tuple[str, Any]:
    try:
        return _SCALARS[type(t)]
    except KeyError:
        raise UnsupportedType(f"{where}: {type(t).__name__} cannot be described for JSON Schema readers") from None


def _field_plan(f: _inspect.Field, owner: str) -> tuple[dict[str, object], Any, str]:
    """(JSON Schema of the field, the annotation the decoder reads it with, kind:
    scalar|float|floats|struct|structs).

    A nested Struct (a setpoint triplet's setpoints) becomes an object with its own schema, and a list of them
    (a mission's items) an array of such objects."""
    where = f"{owner}.{f.name}"
    t = f.type
    if isinstance(t, _inspect.StructType):
        return _nested_schema(t.cls), msgspec.Raw, "struct"
    if isinstance(t, _inspect.TupleType):
        kinds = {_scalar(i, where) for i in t.item_types}
        if len(kinds) != 1:
            raise UnsupportedType(f"{where}: a tuple of mixed item types has no JSON Schema array form")
        name, py = kinds.pop()
        n = len(t.item_types)
        item = float | str if py is float else py
        schema = {"type": "array", "items": {"type": name}, "minItems": n, "maxItems": n}
        return schema, tuple[(item,) * n], "floats" if py is float else "scalar"
    if isinstance(t, _inspect.ListType) and isinstance(t.item_type, _inspect.StructType):
        return {"type": "array", "items": _nested_schema(t.item_type.cls)}, list[msgspec.Raw], "structs"
    if isinstance(t, _inspect.VarTupleType | _inspect.ListType):
        name, py = _scalar(t.item_type, where)
        item = float | str if py is float else py
        schema: dict[str, object] = {"type": "array", "items": {"type": name}}
        meta: dict[str, int] = {}
        if t.min_length is not None:
            schema["minItems"] = meta["min_length"] = t.min_length
        if t.max_length is not None:
            schema["maxItems"] = meta["max_length"] = t.max_length
        container = tuple[item, ...] if isinstance(t, _inspect.VarTupleType) else list[item]
        annotation = Annotated[container, msgspec.Meta(**meta)] if meta else container
        return schema, annotation, "floats" if py is float else "scalar"
    name, py = _scalar(t, where)
    return {"type": name}, (float | str if py is float else py), "float" if py is float else "scalar"


def _nested_schema(cls: type[msgspec.Struct]) -> dict[str, object]:
    return {k: v for k, v in json.loads(codec_for(cls).schema).items() if k != "$schema"}


class JsonMessageCodec:
    """Encodes one message type to a JSON object and back, exactly; also its JSON Schema.

    ``encode`` takes about 0.7 µs for a SensorGyro and 3 µs for a VehicleLocalPosition (the
    largest message); ``decode`` about as much.
    """

    __slots__ = (
        "_decoder",
        "_encoder",
        "_float_fields",
        "_float_seq_fields",
        "_out_type",
        "_struct_fields",
        "_struct_seq_fields",
        "field_names",
        "msg_type",
        "schema",
        "schema_name",
    )

    def __init__(self, msg_type: type[msgspec.Struct]) -> None:
        info = _inspect.type_info(msg_type)
        if not isinstance(info, _inspect.StructType):
            raise UnsupportedType(f"{msg_type!r} is not a msgspec Struct")
        owner = msg_type.__name__
        properties: dict[str, object] = {}
        read_fields: list[tuple[str, Any]] = []
        floats: list[int] = []
        float_seqs: list[int] = []
        structs: list[tuple[int, JsonMessageCodec]] = []
        struct_seqs: list[tuple[int, JsonMessageCodec]] = []
        for i, f in enumerate(info.fields):
            schema, annotation, kind = _field_plan(f, owner)
            properties[f.name] = schema
            read_fields.append((f.name, annotation))
            if kind == "float":
                floats.append(i)
            elif kind == "floats":
                float_seqs.append(i)
            elif kind == "struct":
                structs.append((i, codec_for(f.type.cls)))
            elif kind == "structs":
                struct_seqs.append((i, codec_for(f.type.item_type.cls)))
        self.msg_type = msg_type
        self.schema_name = owner
        self.field_names = tuple(f.name for f in info.fields)
        doc = (msg_type.__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
        self.schema = json.dumps(
            {
                "$schema": "https://json-schema.org/draft/2020-12/schema",
                "title": owner,
                "description": f"{doc} {NONFINITE_RULE}".strip(),
                "type": "object",
                "properties": properties,
                "required": list(self.field_names),
            },
            separators=(",", ":"),
        ).encode()
        self._float_fields = tuple(floats)
        self._float_seq_fields = tuple(float_seqs)
        self._struct_fields = tuple(structs)
        self._struct_seq_fields = tuple(struct_seqs)
        # Object-form twins of the array-like message: one to write (values unchecked), one to read.
        self._out_type = msgspec.defstruct(f"{owner}Json", [(n, object) for n in self.field_names], gc=False)
        self._encoder = msgspec.json.Encoder()
        self._decoder = msgspec.json.Decoder(msgspec.defstruct(f"{owner}JsonIn", read_fields, gc=False))

    def encode(self, msg: msgspec.Struct) -> bytes:
        """The message as a JSON object, non-finite floats spelled as strings."""
        values = list(msgspec.structs.astuple(msg))
        for i in self._float_fields:
            v = values[i]
            if v - v:  # NaN for NaN and ±inf, 0.0 for every finite float
                values[i] = nonfinite_name(v)
        for i in self._float_seq_fields:
            seq = values[i]
            total = sum(seq)
            if total - total:
                values[i] = [nonfinite_name(v) if v - v else v for v in seq]
        for i, nested in self._struct_fields:
            values[i] = msgspec.Raw(nested.encode(values[i]))
        for i, nested in self._struct_seq_fields:
            values[i] = [msgspec.Raw(nested.encode(item)) for item in values[i]]
        return self._encoder.encode(self._out_type(*values))

    def decode(self, data: bytes | memoryview) -> Any:
        """The message a JSON object encodes; raises msgspec.ValidationError/DecodeError if it does not fit."""
        values = list(msgspec.structs.astuple(self._decoder.decode(data)))
        for i in self._float_fields:
            v = values[i]
            if type(v) is str:
                values[i] = _nonfinite_value(v)
        for i in self._float_seq_fields:
            seq = values[i]
            if str in map(type, seq):
                values[i] = type(seq)(_nonfinite_value(v) if type(v) is str else v for v in seq)
        for i, nested in self._struct_fields:
            values[i] = nested.decode(values[i])
        for i, nested in self._struct_seq_fields:
            values[i] = [nested.decode(raw) for raw in values[i]]
        return self.msg_type(*values)


def _nonfinite_value(name: str) -> float:
    try:
        return NONFINITE_VALUES[name]
    except KeyError:
        raise msgspec.ValidationError(f"{name!r} is not a number nor one of {', '.join(NONFINITE_NAMES)}") from None


@functools.cache
def codec_for(msg_type: type[msgspec.Struct]) -> JsonMessageCodec:
    """The (shared) codec of a message type; raises UnsupportedType."""
    return JsonMessageCodec(msg_type)


def schema_decoder(schema_json: bytes | str) -> Callable[[bytes | memoryview], dict[str, Any]]:
    """A decoder for JSON messages of a type this build does not have, driven by their recorded schema.

    It returns the fields as a dict in recorded order, with non-finite floats restored wherever the
    schema says "number", also in nested objects and arrays of them; arrays stay lists.
    """
    restore = _restorer(json.loads(schema_json))

    def decode(data: bytes | memoryview) -> dict[str, Any]:
        fields = msgspec.json.decode(data)
        if not isinstance(fields, dict):
            raise msgspec.ValidationError("expected a JSON object")
        return restore(fields)

    return decode


def _restorer(schema: dict[str, Any]) -> Callable[[Any], Any]:
    """A function giving a JSON value of ``schema`` back with its non-finite floats as floats."""
    kind = schema.get("type")
    if kind == "number":
        return lambda v: _nonfinite_value(v) if type(v) is str else v
    if kind == "array":
        item = _restorer(schema.get("items", {}))
        if item is _unchanged:
            return _unchanged
        return lambda v: [item(i) for i in v] if type(v) is list else v
    if kind == "object":
        fields = {name: _restorer(p) for name, p in schema.get("properties", {}).items()}
        fields = {name: f for name, f in fields.items() if f is not _unchanged}

        def restore(v: Any) -> Any:
            if type(v) is dict:
                for name, f in fields.items():
                    if name in v:
                        v[name] = f(v[name])
            return v

        return restore
    return _unchanged


def _unchanged(v: Any) -> Any:
    return v
