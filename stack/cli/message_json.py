"""Messages as JSON for ``stack topic``: field values in (``pub``) checked against the schema, and fields
picked out by path (``echo --field``).

Messages travel as msgpack arrays (``array_like``), nested structs too (a mission's items), but a user
writes JSON objects by field name at every level; each struct type has a twin that takes objects, refuses
unknown fields and keeps the defaults, and what it accepts is rebuilt into the real types.
"""

from __future__ import annotations

import functools
import json
from typing import Annotated, Any, Union, get_args, get_origin

import msgspec

from stack.bus.topics import HEADER, MAX_SAMPLE_BYTES
from stack.msg.base import Message
from stack.msg.registry import message_type

_REAL: dict[type, type[msgspec.Struct]] = {}
"""Each by-name twin → the struct type it checks for."""


@functools.cache
def _by_name(struct: type[msgspec.Struct]) -> type[msgspec.Struct]:
    """The twin of ``struct`` that takes a JSON object by field name, unknown fields refused."""
    fields = []
    for f in msgspec.structs.fields(struct):
        default = msgspec.field(default_factory=f.default_factory) if f.default is msgspec.NODEFAULT else f.default
        fields.append((f.name, _by_name_type(f.type), default))
    twin = msgspec.defstruct(struct.__name__, fields, kw_only=True, forbid_unknown_fields=True)
    _REAL[twin] = struct
    return twin


def _by_name_type(t: Any) -> Any:
    """``t`` with every struct type in it replaced by its by-name twin."""
    if isinstance(t, type) and issubclass(t, msgspec.Struct):
        return _by_name(t)
    origin, args = get_origin(t), get_args(t)
    if origin is None or not args:
        return t
    if origin is Annotated:
        return Annotated[(_by_name_type(args[0]), *args[1:])]
    if origin is Union:
        return Union[tuple(_by_name_type(a) for a in args)]  # noqa: UP007 (built from a tuple)
    return origin[tuple(_by_name_type(a) for a in args)]


def _real(value: Any) -> Any:
    """A checked value with every twin instance rebuilt as the real struct."""
    if isinstance(value, msgspec.Struct):
        real = _REAL[type(value)]
        return real(**{name: _real(getattr(value, name)) for name in value.__struct_fields__})
    if isinstance(value, list):
        return [_real(v) for v in value]
    if isinstance(value, tuple):
        return tuple(_real(v) for v in value)
    return value


def parse_message(topic: str, text: str) -> Message:
    """A message from JSON field values, checked against the topic's schema. Raises ValueError (and
    UnknownTopic) with one line saying what is wrong."""
    msg_type = message_type(topic)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"not valid JSON: {e}") from None
    if not isinstance(data, dict):
        raise ValueError("expected a JSON object of field values, e.g. '{\"roll\": 0.1}'")
    try:
        checked = msgspec.convert(data, _by_name(msg_type))
    except msgspec.ValidationError as e:
        raise ValueError(f"{msg_type.__name__}: {e}".replace("$.", "")) from None
    msg = _real(checked)
    size = len(msgspec.msgpack.encode(msg)) + HEADER.size
    if size > MAX_SAMPLE_BYTES:
        raise ValueError(
            f"{msg_type.__name__}: {size} bytes, more than the {MAX_SAMPLE_BYTES} one message on the bus may have"
        )
    return msg


def as_dict(value: Any) -> Any:
    """A message as builtins by field name at every level (what ``parse_message`` takes back)."""
    if isinstance(value, msgspec.Struct):
        return {name: as_dict(getattr(value, name)) for name in value.__struct_fields__}
    if isinstance(value, list | tuple):
        return [as_dict(v) for v in value]
    return value


def parse_field_paths(options: list[str]) -> list[str]:
    """``--field`` values, each one path or several separated by commas."""
    return [path.strip() for option in options for path in option.split(",") if path.strip()]


def pick(data: Any, path: str) -> Any:
    """The value at a dotted path (``items.0.north``, ``q.0``) in builtins. Raises KeyError naming the
    part of the path that is not there."""
    for i, part in enumerate(path.split(".")):
        where = ".".join(path.split(".")[: i + 1])
        if isinstance(data, dict):
            if part not in data:
                raise KeyError(f"no field '{where}' (fields: {', '.join(data)})")
            data = data[part]
        elif isinstance(data, list | tuple):
            try:
                data = data[int(part)]
            except (ValueError, IndexError):
                raise KeyError(f"'{where}': index must be 0…{len(data) - 1}") from None
        else:
            raise KeyError(f"'{where}': {'.'.join(path.split('.')[:i]) or 'the message'} has no fields")
    return data
