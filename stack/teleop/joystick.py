"""The Linux joystick device's event stream (``Documentation/input/joydev/joystick-api.rst``).

Reading ``/dev/input/js*`` gives 8-byte ``struct js_event`` records in the host's byte order: ``__u32 time``
(ms), ``__s16 value`` (an axis −32767..32767, a button 0 or 1), ``__u8 type`` (JS_EVENT_BUTTON 1, JS_EVENT_AXIS
2, or'ed with JS_EVENT_INIT 0x80 for the synthetic events that give every axis's and button's state when the
device is opened) and ``__u8 number``. A read may end inside a record (a pipe standing in for the device), so the
decoder keeps the rest for the next; a record of another type is counted and skipped.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

JS_EVENT = struct.Struct("=IhBB")
JS_EVENT_BUTTON = 0x01
JS_EVENT_AXIS = 0x02
JS_EVENT_INIT = 0x80
AXIS_MAX = 32767


class JsEvent(NamedTuple):
    time_ms: int
    value: int
    type: int
    number: int

    @property
    def init(self) -> bool:
        return bool(self.type & JS_EVENT_INIT)

    @property
    def kind(self) -> int:
        """JS_EVENT_BUTTON or JS_EVENT_AXIS."""
        return self.type & ~JS_EVENT_INIT


class JsDecoder:
    def __init__(self) -> None:
        self._rest = b""
        self.malformed = 0
        """Records of no known type, skipped."""

    def feed(self, data: bytes) -> list[JsEvent]:
        buf = self._rest + data
        whole = len(buf) - len(buf) % JS_EVENT.size
        self._rest = buf[whole:]
        events = []
        for record in JS_EVENT.iter_unpack(buf[:whole]):
            event = JsEvent(*record)
            if event.kind in (JS_EVENT_BUTTON, JS_EVENT_AXIS):
                events.append(event)
            else:
                self.malformed += 1
        return events
