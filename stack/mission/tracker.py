"""Progress along a mission: the current item, when it counts as reached, and what to fly next.

Follows PX4 navigator's mission logic (``MissionBlock::is_mission_item_reached_or_completed`` for a
multicopter, and the ``mission_result`` it publishes):

* a waypoint (or timed loiter) is reached once within its acceptance radius (NAV_ACC_RAD when the item
  gives none) horizontally and NAV_MC_ALT_RAD vertically — latched from then on; then, if the item sets a
  heading, once the yaw error is below MIS_YAW_ERR (or MIS_YAW_TMT seconds have passed, when that is ≥ 0);
  then after the item's hold time;
* a takeoff is reached at its altitude (within NAV_MC_ALT_RAD); a landing when the land detector says
  landed; an unlimited loiter is reached on arrival but never left; a speed change takes effect at once;
* for a fixed-wing (``fixed_wing=True``, PX4's fixed-wing branches of the same function) the vertical
  acceptance is NAV_FW_ALT_RAD, a waypoint's horizontal acceptance is at least the guidance's switching
  distance (``update``'s ``acceptance_radius``, PX4 ``Navigator::get_acceptance_radius``), and a loiter
  item is reached on its circle (within a fifth of the radius, or NAV_ACC_RAD if larger, of it);
  LOITER_TURNS then counts the angle flown about the centre until its turns are done (a multicopter takes
  it as reached on arrival);
* a return-to-launch item hands the vehicle to Return mode (``return_requested``);
* an item without autocontinue is held once reached; after the last item the mission is finished and the
  vehicle stays at the last position.

Positions are local NED metres; item positions are about home, so ``start`` takes home's local position.
Takeoff and landing items without a horizontal position use the vehicle's position when they start.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

from stack.mathlib.scalar import wrap_pi
from stack.mathlib.vector import NAN3, Vec3
from stack.mission.items import (
    LOITER_COMMANDS,
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    Mission,
    MissionItem,
)
from stack.params.binding import ParamSet
from stack.params.param import Param


class TrackerParams(ParamSet):
    """The acceptance radii, the loiter radius and the heading alignment of mission items (the catalogue's)."""

    nav_acc_rad: float
    nav_mc_alt_rad: float
    nav_fw_alt_rad: float
    nav_loiter_rad: float
    mis_yaw_err: float
    mis_yaw_tmt: float


PARAMS: tuple[Param, ...] = TrackerParams.PARAMS
LOITER_ON_CIRCLE_FRACTION = 0.2


class MissionProgress(NamedTuple):
    """``mission_result``-like state plus the setpoint to fly."""

    seq_current: int
    seq_reached: int
    """Index of the last item reached (−1: none yet)."""
    seq_total: int
    finished: bool
    target: Vec3
    """Position to fly to (local NED; z NaN while landing)."""
    target_yaw: float
    """Heading to hold [rad]; NaN leaves it free."""
    previous: Vec3
    """Where the current leg starts (for line following)."""
    cruise_speed: float
    """Speed set by the last speed item [m/s]; NaN for the default."""
    command: int
    """MAV_CMD of the current item."""
    return_requested: bool
    """A return-to-launch item was reached: switch to Return mode."""


class MissionTracker:
    """``start(now_us, position, first_index, home_ned)`` when the mission starts or resumes, then
    ``update(now_us, position, yaw, landed)`` every navigation cycle."""

    __slots__ = (
        "_cruise_speed",
        "_finished",
        "_fixed_wing",
        "_home",
        "_items",
        "_loiter_angle",
        "_loiter_bearing",
        "_p",
        "_position_reached_us",
        "_previous",
        "_return_requested",
        "_seq",
        "_seq_reached",
        "_target",
        "_yaw_reached_us",
    )

    def __init__(
        self,
        mission: Mission | Sequence[MissionItem],
        params: Mapping[str, object] | None = None,
        fixed_wing: bool = False,
    ) -> None:
        self._items: tuple[MissionItem, ...] = tuple(mission)
        self._fixed_wing = fixed_wing
        self._loiter_angle = 0.0
        self._loiter_bearing = math.nan
        self._home: Vec3 = (0.0, 0.0, 0.0)
        self._seq = 0
        self._seq_reached = -1
        self._finished = False
        self._return_requested = False
        self._target: Vec3 = NAN3
        self._previous: Vec3 = NAN3
        self._cruise_speed = math.nan
        self._position_reached_us = -1
        self._yaw_reached_us = -1
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        self._p = TrackerParams.from_params(params)

    @property
    def current(self) -> MissionItem | None:
        return self._items[self._seq] if self._items else None

    @property
    def progress(self) -> MissionProgress:
        """The state as of the last ``start`` or ``update``."""
        return self._progress()

    def replace_items(self, mission: Mission | Sequence[MissionItem]) -> None:
        """The same items placed elsewhere (:func:`stack.mission.items.about_home`); the progress is kept and the
        current target follows at the next ``start``."""
        items = tuple(mission)
        if [i.command for i in items] != [i.command for i in self._items]:
            raise ValueError("replace_items takes the same items, placed elsewhere")
        self._items = items

    def start(
        self, now_us: int, position: Vec3, first_index: int = 0, home_ned: Vec3 = (0.0, 0.0, 0.0)
    ) -> MissionProgress:
        """Begin at ``first_index`` (−1: resume at the current item) with home at ``home_ned``."""
        if not self._items:
            raise ValueError("cannot start an empty mission")
        if not -1 <= first_index < len(self._items):
            raise ValueError(f"first item {first_index} is outside 0…{len(self._items) - 1}")
        self._home = home_ned
        self._finished = False
        self._return_requested = False
        self._previous = position
        self._activate(self._seq if first_index < 0 else first_index, position)
        return self._progress()

    def update(
        self, now_us: int, position: Vec3, yaw: float, landed: bool, acceptance_radius: float = math.nan
    ) -> MissionProgress:
        """``acceptance_radius``: a fixed-wing guidance's waypoint switching distance (NaN: none)."""
        if self._finished or not self._items:
            return self._progress()
        item = self._items[self._seq]
        if self._item_complete(item, now_us, position, yaw, landed, acceptance_radius):
            self._seq_reached = self._seq
            if item.command == MAV_CMD_NAV_LAND or self._seq == len(self._items) - 1:
                self._finished = True
            elif item.autocontinue and item.command != MAV_CMD_NAV_LOITER_UNLIM:
                self._previous = self._target
                self._activate(self._seq + 1, position)
        return self._progress()

    def _activate(self, index: int, position: Vec3) -> None:
        """Make ``index`` current, applying instant items (speed, return) on the way."""
        while True:
            self._seq = index
            self._position_reached_us = -1
            self._yaw_reached_us = -1
            self._loiter_angle = 0.0
            self._loiter_bearing = math.nan
            item = self._items[index]
            if item.command == MAV_CMD_DO_CHANGE_SPEED:
                self._cruise_speed = item.speed
            elif item.command == MAV_CMD_NAV_RETURN_TO_LAUNCH:
                self._return_requested = True
                self._finished = True
                self._seq_reached = index
                return
            else:
                self._target = self._item_target(item, position)
                return
            self._seq_reached = index
            if index == len(self._items) - 1:
                self._finished = True
                return
            index += 1

    def _item_target(self, item: MissionItem, position: Vec3) -> Vec3:
        hx, hy, hz = self._home
        north = position[0] if math.isnan(item.north) else hx + item.north
        east = position[1] if math.isnan(item.east) else hy + item.east
        if item.command == MAV_CMD_NAV_LAND:
            down = math.nan
        elif math.isnan(item.down):
            down = position[2]
        else:
            down = hz + item.down
        return (north, east, down)

    def loiter_radius(self, item: MissionItem) -> float:
        """The item's loiter radius [m] (sign: + clockwise), NAV_LOITER_RAD when it gives none."""
        return item.loiter_radius if math.isfinite(item.loiter_radius) else self._p.nav_loiter_rad

    def _item_complete(
        self, item: MissionItem, now_us: int, position: Vec3, yaw: float, landed: bool, guidance_radius: float
    ) -> bool:
        p = self._p
        target = self._target
        altitude_radius = p.nav_fw_alt_rad if self._fixed_wing else p.nav_mc_alt_rad
        if item.command == MAV_CMD_NAV_LAND:
            return landed
        if item.command == MAV_CMD_NAV_TAKEOFF:
            return position[2] <= target[2] + altitude_radius
        orbiting = self._fixed_wing and item.command in LOITER_COMMANDS
        if self._position_reached_us < 0:
            radius = item.acceptance_radius if item.acceptance_radius > 0.0 else p.nav_acc_rad
            horizontal = math.hypot(position[0] - target[0], position[1] - target[1])
            if orbiting:
                circle = abs(self.loiter_radius(item))
                if abs(horizontal - circle) > max(LOITER_ON_CIRCLE_FRACTION * circle, radius):
                    return False
            else:
                if self._fixed_wing and guidance_radius > radius:
                    radius = guidance_radius
                if horizontal > radius:
                    return False
            if abs(position[2] - target[2]) > altitude_radius:
                return False
            self._position_reached_us = now_us
        if orbiting and item.command == MAV_CMD_NAV_LOITER_TURNS:
            bearing = math.atan2(position[1] - target[1], position[0] - target[0])
            if math.isfinite(self._loiter_bearing):
                self._loiter_angle += wrap_pi(bearing - self._loiter_bearing)
            self._loiter_bearing = bearing
            if abs(self._loiter_angle) < 2.0 * math.pi * item.loiter_turns:
                return False
        if self._yaw_reached_us < 0:
            if math.isfinite(item.yaw):
                aligned = abs(wrap_pi(yaw - item.yaw)) <= math.radians(p.mis_yaw_err)
                timeout = p.mis_yaw_tmt
                timed_out = timeout >= 0.0 and now_us - self._position_reached_us >= timeout * 1e6
                if not (aligned or timed_out):
                    return False
            self._yaw_reached_us = now_us
        return now_us - self._yaw_reached_us >= item.hold_time * 1e6

    def _progress(self) -> MissionProgress:
        item = self._items[self._seq] if self._items else None
        return MissionProgress(
            seq_current=self._seq,
            seq_reached=self._seq_reached,
            seq_total=len(self._items),
            finished=self._finished,
            target=self._target,
            target_yaw=item.yaw if item is not None else math.nan,
            previous=self._previous,
            cruise_speed=self._cruise_speed,
            command=item.command if item is not None else 0,
            return_requested=self._return_requested,
        )
