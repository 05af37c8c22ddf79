"""Navigation: missions uploaded to the vehicle, their progress, and what the commander asks the navigator.

PX4 keeps missions in dataman and hands the navigator a ``mission`` topic naming them; here the
``mission`` message carries its items, already converted to local NED metres about home by the
uploader (``stack cmd mission``), which read home from the vehicle. The flight-mode manager checks
it and answers with ``mission_result``, which also reports progress, as PX4's navigator does.
"""

from __future__ import annotations

import msgspec

from stack.msg.base import F3, NAN, NAN3, Message


class MissionItemEntry(msgspec.Struct, array_like=True, gc=False):
    """One mission item (see :class:`stack.mission.items.MissionItem`): MAVLink command and frame,
    local NED position about home (NaN: where the vehicle is), geodetic position as given."""

    command: int = 16
    frame: int = 1
    north: float = NAN
    east: float = NAN
    down: float = NAN
    lat: float = NAN
    lon: float = NAN
    alt: float = NAN
    acceptance_radius: float = 0.0
    yaw: float = NAN
    hold_time: float = 0.0
    speed: float = NAN
    autocontinue: bool = True
    loiter_radius: float = NAN
    loiter_turns: float = NAN


class Mission(Message):
    """A mission upload: every item, and the home (geodetic) its local positions are about."""

    mission_id: int = 0
    items: list[MissionItemEntry] = msgspec.field(default_factory=list)
    home_lat: float = NAN
    home_lon: float = NAN
    home_alt: float = NAN
    source: str = ""


class MissionResult(Message):
    """The navigator's verdict on the uploaded mission and its progress (PX4 ``MissionResult``)."""

    mission_id: int = 0
    seq_reached: int = -1
    seq_current: int = 0
    seq_total: int = 0
    valid: bool = False
    warning: bool = False
    finished: bool = False
    failure: bool = False
    reason: str = ""


class NavigationRequest(Message):
    """What the commander asks the navigator to fly beyond the mode itself: the takeoff altitude, the
    latest go-to target and the latest mission start (counters say when a new one was accepted)."""

    NAN_MEANS_NOT_CONTROLLED = True

    takeoff_altitude: float = NAN
    takeoff_yaw: float = NAN
    reposition: F3 = NAN3
    reposition_yaw: float = NAN
    reposition_speed: float = NAN
    reposition_counter: int = 0
    mission_start_index: int = 0
    mission_start_counter: int = 0
