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
        source=mission.source,
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
