"""A mission on the bus: conversion between :class:`~stack.mission.items.Mission` and the ``mission`` message.

The message carries every item with the same fields as :class:`~stack.mission.items.MissionItem` (the
index is the position in the list) and the geodetic home the local positions are about (NaN: none).
"""

from __future__ import annotations

import math
import zlib

import msgspec

from stack.mission.items import GeoPoint, Mission, MissionItem
from stack.msg import navigation

_ENTRY_FIELDS = navigation.MissionItemEntry.__struct_fields__
_encoder = msgspec.msgpack.Encoder()

MAX_ITEMS = 400
"""The most items a mission may have: its ``mission`` message must be one sample of the bus
(``stack.bus.topics.MAX_SAMPLE_BYTES``), and 400 items in their largest encoding (twelve 8-byte floats each) are
46 kB. PX4 takes 2000 on a flight controller (``NUM_MISSIONS_SUPPORTED``, ``src/modules/navigator/navigation.h``)."""
MAX_SOURCE_CHARS = 200
"""The end of a longer ``source`` (a file's path) is what the message carries."""


def too_many_items(count: int) -> str:
    """Why a mission of ``count`` items is refused, or "" when it is not too long."""
    return f"{count} items, more than the {MAX_ITEMS} a mission may have" if count > MAX_ITEMS else ""


def _entries(mission: Mission) -> list[navigation.MissionItemEntry]:
    return [navigation.MissionItemEntry(**{f: getattr(item, f) for f in _ENTRY_FIELDS}) for item in mission]


def mission_id_for(mission: Mission) -> int:
    """A stable, non-zero 31-bit id from the items' content (CRC-32 of their wire encoding)."""
    return (zlib.crc32(_encoder.encode(_entries(mission))) & 0x7FFF_FFFF) or 1


def mission_message(mission: Mission, home: GeoPoint | None, mission_id: int) -> navigation.Mission:
    """The ``mission`` message for an upload: one entry per item, and ``home`` (None: NaN)."""
    lat, lon, alt = (home.lat, home.lon, home.alt) if home is not None else (math.nan, math.nan, math.nan)
    return navigation.Mission(
        mission_id=mission_id,
        items=_entries(mission),
        home_lat=lat,
        home_lon=lon,
        home_alt=alt,
        source=mission.source[-MAX_SOURCE_CHARS:],
    )


def mission_from_message(msg: navigation.Mission) -> Mission:
    """The mission a ``mission`` message carries; no home when its latitude or longitude is NaN."""
    items = tuple(
        MissionItem(index=i, **{f: getattr(entry, f) for f in _ENTRY_FIELDS}) for i, entry in enumerate(msg.items)
    )
    home = None
    if not (math.isnan(msg.home_lat) or math.isnan(msg.home_lon)):
        home = GeoPoint(msg.home_lat, msg.home_lon, msg.home_alt)
    return Mission(items, home, msg.source)
