"""The MAVLink parameter protocol (PARAM_REQUEST_LIST / PARAM_REQUEST_READ / PARAM_SET → PARAM_VALUE), I/O-free.

It serves the stack's parameters through a :class:`ParamSource` (listing them and setting one), which the
module runs on a worker thread: the protocol hands out jobs (:meth:`ParamProtocol.take_jobs`) and takes their
results. As PX4 (``src/modules/mavlink/mavlink_parameters.cpp``) it advertises MAV_PROTOCOL_CAPABILITY_PARAM_
ENCODE_BYTEWISE: an integer parameter is MAV_PARAM_TYPE_INT32 with its 4 bytes carried as they are in
PARAM_VALUE's float field (a C cast would turn 4 into 4.0, which MAVSDK and QGroundControl misread); a float
parameter is REAL32. Booleans are INT32 0/1; string parameters are not served, nor names longer than
PARAM_VALUE's 16 characters, nor integers beyond int32.

The list is sorted by name: ``param_index`` is the position in it and ``param_count`` its length, the same in
every PARAM_VALUE of one listing. A set whose type does not match the parameter's (PX4 refuses those too) or
that the parameter's definition refuses (range, choices) changes nothing and is answered with the unchanged
value and a reason, which the module sends as STATUSTEXT; an unknown name gets no PARAM_VALUE (there is no
value to send), only the reason. Every change, whoever made it (this link, another one, ``stack param set``),
is broadcast as PARAM_VALUE once the module lists the parameters again on ``parameter_update``.
"""

from __future__ import annotations

import math
import struct
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink2

from stack.params.param import ParamError

ParamNumber = int | float
INT32 = mavlink2.MAV_PARAM_TYPE_INT32
REAL32 = mavlink2.MAV_PARAM_TYPE_REAL32
PARAM_ID_LEN = 16
INT32_RANGE = (-(2**31), 2**31 - 1)


class ParamSource(Protocol):
    """Where the parameters live (the stack's modules, through the bus)."""

    def list(self) -> list[tuple[str, ParamNumber, bool]]:
        """Every numeric parameter: (name, value, is_int)."""
        ...

    def set(self, name: str, value: ParamNumber) -> ParamNumber:
        """Set one everywhere it is used; returns the new value or raises ParamError with the reason."""
        ...


@dataclass(frozen=True)
class Entry:
    name: str
    value: ParamNumber
    is_int: bool


@dataclass(frozen=True)
class ListJob:
    pass


@dataclass(frozen=True)
class SetJob:
    name: str
    value: ParamNumber


def encode(value: ParamNumber, is_int: bool) -> tuple[float, int]:
    """PARAM_VALUE's (param_value, param_type): an int's bytes as they are, bytewise."""
    if is_int:
        return struct.unpack("<f", struct.pack("<i", int(value)))[0], INT32
    return float(value), REAL32


def decode(param_value: float, param_type: int) -> ParamNumber:
    """PARAM_SET's value: the int32 whose bytes the float carries, or the float itself (shortest decimal)."""
    if param_type == INT32:
        return struct.unpack("<i", struct.pack("<f", param_value))[0]
    return float32_decimal(param_value)


def float32_decimal(value: float) -> float:
    """The shortest decimal that is the same float32 (0.2, not 0.200000003): what the user typed."""
    if not math.isfinite(value):
        return value
    bits = struct.pack("<f", value)
    for digits in range(1, 10):
        candidate = float(f"{value:.{digits}g}")
        if struct.pack("<f", candidate) == bits:
            return candidate
    return value


class ParamProtocol:
    def __init__(self, own: tuple[int, int]) -> None:
        self.own = own
        self.entries: list[Entry] = []
        self.index: dict[str, int] = {}
        self.loaded = False
        self.skipped = 0
        """Parameters not served (names over 16 characters)."""
        self.ignored = 0
        """Requests that could not be answered (unknown index, unsupported type...)."""
        self._answers: deque[mavlink2.MAVLink_param_value_message] = deque()
        self._listing: deque[mavlink2.MAVLink_param_value_message] = deque()
        self._jobs: deque[ListJob | SetJob] = deque()
        self._list_pending = False
        self._list_again = False
        self._want_all = False
        self._deferred_reads: list[mavlink2.MAVLink_param_request_read_message] = []

    # -- requests from the link ----------------------------------------------------------------------

    def _for_us(self, target_system: int, target_component: int) -> bool:
        return target_system in (0, self.own[0]) and target_component in (0, self.own[1])

    def on_request_list(self, msg: mavlink2.MAVLink_param_request_list_message) -> None:
        if not self._for_us(msg.target_system, msg.target_component):
            return
        self._listing.clear()
        self._want_all = True
        self.refresh()

    def on_request_read(self, msg: mavlink2.MAVLink_param_request_read_message) -> None:
        if not self._for_us(msg.target_system, msg.target_component):
            return
        if not self.loaded:
            self._deferred_reads.append(msg)
            self.refresh()
            return
        if msg.param_index >= 0:
            i = msg.param_index if msg.param_index < len(self.entries) else None
        else:
            i = self.index.get(msg.param_id)
        if i is None:
            self.ignored += 1
            return
        self._answers.append(self._value(i))

    def on_set(self, msg: mavlink2.MAVLink_param_set_message) -> str:
        """Queue the set; returns why it is refused at once ("" when it goes on to the source)."""
        if not self._for_us(msg.target_system, msg.target_component):
            return ""
        i = self.index.get(msg.param_id)
        if i is None:
            self.ignored += 1
            return f"Parameter {msg.param_id} not set: no such parameter"
        entry = self.entries[i]
        wanted = INT32 if entry.is_int else REAL32
        if msg.param_type != wanted:
            self._answers.append(self._value(i))
            kind = "INT32" if entry.is_int else "REAL32"
            return f"Parameter {entry.name} not set: it is {kind}, the request gave type {msg.param_type}"
        self._jobs.append(SetJob(entry.name, decode(msg.param_value, msg.param_type)))
        return ""

    def refresh(self) -> None:
        """List the parameters again (``parameter_update``: something changed, broadcast what did)."""
        if self._list_pending:
            self._list_again = True
            return
        self._list_pending = True
        self._jobs.append(ListJob())

    # -- results from the source ---------------------------------------------------------------------

    def on_list(self, params: Iterable[tuple[str, ParamNumber, bool]]) -> None:
        entries = []
        self.skipped = 0
        for name, value, is_int in params:
            if len(name) > PARAM_ID_LEN or (is_int and not INT32_RANGE[0] <= int(value) <= INT32_RANGE[1]):
                self.skipped += 1
                continue
            entries.append(Entry(name, int(value) if is_int else float(value), is_int))
        entries.sort(key=lambda e: e.name)
        before = {e.name: e for e in self.entries} if self.loaded else None
        self.entries = entries
        self.index = {e.name: i for i, e in enumerate(entries)}
        self.loaded = True
        self._list_pending = False
        if before is not None:
            for i, e in enumerate(entries):
                if before.get(e.name) not in (None, e):
                    self._answers.append(self._value(i))
        if self._want_all:
            self._want_all = False
            self._listing.extend(self._value(i) for i in range(len(entries)))
        reads, self._deferred_reads = self._deferred_reads, []
        for read in reads:
            self.on_request_read(read)
        if self._list_again:
            self._list_again = False
            self.refresh()

    def on_list_failed(self) -> None:
        self._list_pending = False
        self._list_again = False

    def on_set_result(self, name: str, result: ParamNumber | ParamError) -> str:
        """The source's answer to a set; returns the refusal's reason ("" when it was set)."""
        i = self.index.get(name)
        if i is None:
            return ""
        entry = self.entries[i]
        if isinstance(result, ParamError):
            self._answers.append(self._value(i))
            return f"Parameter {name} not set: {result}"
        self.entries[i] = Entry(name, int(result) if entry.is_int else float(result), entry.is_int)
        self._answers.append(self._value(i))
        return ""

    # -- what to do and send -------------------------------------------------------------------------

    def take_jobs(self) -> list[ListJob | SetJob]:
        jobs = list(self._jobs)
        self._jobs.clear()
        return jobs

    def take(self, limit: int) -> list[mavlink2.MAVLink_param_value_message]:
        """Up to ``limit`` PARAM_VALUE to send now: answers first, then the listing in index order."""
        out = []
        for queue in (self._answers, self._listing):
            while queue and len(out) < limit:
                out.append(queue.popleft())
        return out

    def sending(self) -> bool:
        return bool(self._answers or self._listing)

    def _value(self, i: int) -> mavlink2.MAVLink_param_value_message:
        e = self.entries[i]
        value, kind = encode(e.value, e.is_int)
        return mavlink2.MAVLink_param_value_message(e.name.encode(), value, kind, len(self.entries), i)
