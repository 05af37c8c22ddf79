"""The MAVLink mission protocol (https://mavlink.io/en/services/mission.html), vehicle side, I/O-free.

Upload: MISSION_COUNT → MISSION_REQUEST_INT for each item in turn (repeated every RETRY_US until it comes, for
PROTOCOL_TIMEOUT_US at most) → MISSION_ITEM_INT... After the last item the module converts the items and
publishes the ``mission`` message (:class:`Upload`); the MISSION_ACK follows the navigator's verdict
(``mission_result``): ACCEPTED, or an error with the navigator's reason. MISSION_COUNT 0 and MISSION_CLEAR_ALL
clear the mission (:class:`Clear`). One upload at a time: a second sender is DENIED while one is under way.

Download: MISSION_REQUEST_LIST → MISSION_COUNT → MISSION_REQUEST_INT(seq) → MISSION_ITEM_INT(seq), answered
from :attr:`MissionTransfer.items` (the vehicle's mission as the module last saw it) as often as asked.

Only the INT messages are served (MISSION_ITEM_INT, MISSION_REQUEST_INT: the MISSION_INT capability); the legacy
float ones and the fence and rally mission types are answered MAV_MISSION_UNSUPPORTED. MISSION_SET_CURRENT
becomes :class:`SetCurrent`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from pymavlink.dialects.v20 import common as mavlink2

from stack.mission.transfer import too_many_items

RETRY_US = 250_000
"""PX4's MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT (``src/modules/mavlink/mavlink_mission.h``)."""
PROTOCOL_TIMEOUT_US = 5_000_000
"""PX4's MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT."""
VERDICT_TIMEOUT_US = 5_000_000
"""How long the navigator has to judge an uploaded mission."""
MISSION = mavlink2.MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class Upload:
    """Every item of a completed upload, in order: convert, publish, then call ``verdict``."""

    items: list[Any]


@dataclass(frozen=True)
class Clear:
    pass


@dataclass(frozen=True)
class SetCurrent:
    seq: int
    source: tuple[int, int]


@dataclass(frozen=True)
class Refused:
    """An upload refused before its items came, and why (the ground station was answered already)."""

    reason: str


Action = Upload | Clear | SetCurrent | Refused


@dataclass
class _Upload:
    partner: tuple[int, int]
    count: int
    items: list[Any] = field(default_factory=list)
    requested_us: int = 0
    started_us: int = 0
    judging_since_us: int | None = None


class MissionTransfer:
    def __init__(self, own: tuple[int, int]) -> None:
        self.own = own
        self.items: list[mavlink2.MAVLink_mission_item_int_message] = []
        """The vehicle's mission for downloads (MISSION_ITEM_INT, any target; re-addressed when sent)."""
        self.uploads = 0
        self.downloads = 0
        self.refused = 0
        self._upload: _Upload | None = None
        self._out: list[mavlink2.MAVLink_message] = []
        self._actions: list[Action] = []

    def _for_us(self, msg: Any) -> bool:
        return msg.target_system in (0, self.own[0]) and msg.target_component in (0, self.own[1])

    def _ack(self, to: tuple[int, int], result: int, mission_type: int = MISSION) -> None:
        self._out.append(mavlink2.MAVLink_mission_ack_message(to[0], to[1], result, mission_type))
        if result != mavlink2.MAV_MISSION_ACCEPTED:
            self.refused += 1

    def _request(self, upload: _Upload, now_us: int) -> None:
        upload.requested_us = now_us
        seq = len(upload.items)
        self._out.append(mavlink2.MAVLink_mission_request_int_message(*upload.partner, seq, MISSION))

    def _unsupported_type(self, msg: Any, source: tuple[int, int]) -> bool:
        mission_type = getattr(msg, "mission_type", MISSION)
        if mission_type == MISSION:
            return False
        self._ack(source, mavlink2.MAV_MISSION_UNSUPPORTED, mission_type)
        return True

    # -- messages from the link ------------------------------------------------------------------------

    def on_message(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        kind = msg.get_type()
        handler = self._handlers.get(kind)
        if handler is not None and self._for_us(msg):
            handler(self, msg, source, now_us)

    def _on_count(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        if self._unsupported_type(msg, source):
            return
        busy = self._upload
        if busy is not None and busy.partner != source and now_us - busy.started_us < PROTOCOL_TIMEOUT_US:
            self._ack(source, mavlink2.MAV_MISSION_DENIED)
            return
        self._upload = None
        if msg.count == 0:
            self.items = []
            self._actions.append(Clear())
            self._ack(source, mavlink2.MAV_MISSION_ACCEPTED)
            return
        too_many = too_many_items(msg.count)
        if too_many:
            # PX4's answer to more items than it has room for (mavlink_mission.cpp, handle_mission_count).
            self._ack(source, mavlink2.MAV_MISSION_NO_SPACE)
            self._actions.append(Refused(too_many))
            return
        self._upload = _Upload(source, msg.count, started_us=now_us)
        self._request(self._upload, now_us)

    def _on_item_int(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        upload = self._upload
        if upload is None or upload.partner != source or upload.judging_since_us is not None:
            return
        if self._unsupported_type(msg, source):
            self._upload = None
            return
        expected = len(upload.items)
        if msg.seq < expected:
            self._request(upload, now_us)  # a repeat: ask again for the one we wait for
            return
        if msg.seq > expected:
            self._upload = None
            self._ack(source, mavlink2.MAV_MISSION_INVALID_SEQUENCE)
            return
        upload.items.append(msg)
        upload.started_us = now_us
        if len(upload.items) < upload.count:
            self._request(upload, now_us)
            return
        upload.judging_since_us = now_us
        self._actions.append(Upload(list(upload.items)))

    def _on_request_list(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        if self._unsupported_type(msg, source):
            return
        self.downloads += 1
        self._out.append(mavlink2.MAVLink_mission_count_message(*source, len(self.items), MISSION))

    def _on_request_int(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        if self._unsupported_type(msg, source):
            return
        if not 0 <= msg.seq < len(self.items):
            self._ack(source, mavlink2.MAV_MISSION_INVALID_SEQUENCE)
            return
        item = self.items[msg.seq]
        item.target_system, item.target_component = source
        self._out.append(item)

    def _on_clear_all(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        if msg.mission_type not in (MISSION, mavlink2.MAV_MISSION_TYPE_ALL):
            self._ack(source, mavlink2.MAV_MISSION_UNSUPPORTED, msg.mission_type)
            return
        self._upload = None
        self.items = []
        self._actions.append(Clear())
        self._ack(source, mavlink2.MAV_MISSION_ACCEPTED, msg.mission_type)

    def _on_set_current(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        self._actions.append(SetCurrent(msg.seq, source))

    def _on_legacy(self, msg: Any, source: tuple[int, int], now_us: int) -> None:
        self._ack(source, mavlink2.MAV_MISSION_UNSUPPORTED, getattr(msg, "mission_type", MISSION))

    _handlers: ClassVar[dict[str, Any]] = {
        "MISSION_COUNT": _on_count,
        "MISSION_ITEM_INT": _on_item_int,
        "MISSION_REQUEST_LIST": _on_request_list,
        "MISSION_REQUEST_INT": _on_request_int,
        "MISSION_CLEAR_ALL": _on_clear_all,
        "MISSION_SET_CURRENT": _on_set_current,
        "MISSION_ITEM": _on_legacy,
        "MISSION_REQUEST": _on_legacy,
    }

    # -- the module's side -----------------------------------------------------------------------------

    def verdict(self, accepted: bool, mission_result: int = mavlink2.MAV_MISSION_ERROR) -> None:
        """The end of an upload: the navigator accepted the mission, or the conversion or the navigator refused it
        (``mission_result`` then says how)."""
        upload = self._upload
        if upload is None or upload.judging_since_us is None:
            return
        self._upload = None
        if accepted:
            self.uploads += 1
        self._ack(upload.partner, mavlink2.MAV_MISSION_ACCEPTED if accepted else mission_result)

    @property
    def judging(self) -> bool:
        """An upload is complete and waits for its verdict."""
        return self._upload is not None and self._upload.judging_since_us is not None

    def tick(self, now_us: int) -> None:
        """Repeat the outstanding request; give up on a silent partner or a navigator that does not answer."""
        upload = self._upload
        if upload is None:
            return
        if upload.judging_since_us is not None:
            if now_us - upload.judging_since_us > VERDICT_TIMEOUT_US:
                self._upload = None
                self._ack(upload.partner, mavlink2.MAV_MISSION_ERROR)
            return
        if now_us - upload.started_us > PROTOCOL_TIMEOUT_US:
            self._upload = None
            self._ack(upload.partner, mavlink2.MAV_MISSION_OPERATION_CANCELLED)
        elif now_us - upload.requested_us >= RETRY_US:
            self._request(upload, now_us)

    def take(self) -> tuple[list[mavlink2.MAVLink_message], list[Action]]:
        """What to send and what to do, since the last call."""
        out, actions = self._out, self._actions
        self._out, self._actions = [], []
        return out, actions
