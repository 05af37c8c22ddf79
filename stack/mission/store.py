"""The navigator's mission: what was uploaded, whether it was accepted, and what ``mission_result`` says.

Both navigators (the multicopter flight-mode manager and the fixed-wing navigator) keep their mission in a
:class:`MissionStore` and answer the ``mission`` topic with :class:`MissionResultPublisher`, so an upload is
checked, refused and reported the same way whatever flies it (PX4's navigator ``Mission`` and its
``mission_result`` publication: on every change, and once a second).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, NamedTuple

from stack.commander.home import HomePosition
from stack.mathlib.vector import ZERO3, Vec3
from stack.mission import feasibility
from stack.mission.items import GeoPoint, Mission, about_home
from stack.mission.tracker import MissionProgress, MissionTracker
from stack.mission.transfer import mission_from_message
from stack.msg import navigation
from stack.msg.registry import ORB_ID

if TYPE_CHECKING:
    from stack.runtime.module import Module

MISSION_RESULT_REPUBLISH_US = 1_000_000


class MissionStatus(NamedTuple):
    """What ``mission_result`` reports."""

    mission_id: int
    valid: bool
    reason: str
    seq_total: int
    seq_current: int
    seq_reached: int
    finished: bool


class MissionStore:
    """The loaded mission and its tracker; ``load`` checks an upload, ``status`` reports it.

    ``on_replaced`` is called after every upload, accepted or refused: a navigator flying the mission it
    replaced starts over with the new one from its first item, as PX4's navigator does (``Mission::
    onMissionUpdate``), and one flying none holds.
    """

    def __init__(self, fixed_wing: bool = False, on_replaced: Callable[[], None] = lambda: None) -> None:
        self.fixed_wing = fixed_wing
        self._on_replaced = on_replaced
        self.mission: Mission | None = None
        self.tracker: MissionTracker | None = None
        self.mission_id = 0
        self.reason = ""

    def load(self, mission: Mission, mission_id: int, params: Mapping[str, object]) -> str:
        """Take an upload; returns why it was refused ("" when accepted). A refused upload leaves no
        mission, as in PX4 (the vehicle holds an invalid mission until the next upload)."""
        problem = feasibility.mission_problem(mission, params)
        if problem:
            self.refuse(mission_id, problem)
            return problem
        self.mission_id, self.reason, self.mission = mission_id, "", mission
        self.tracker = MissionTracker(mission, params, fixed_wing=self.fixed_wing)
        self._on_replaced()
        return ""

    def refuse(self, mission_id: int, reason: str) -> None:
        """An upload that could not even be read, or failed the checks: no mission, and the reason."""
        self.mission_id, self.reason, self.mission, self.tracker = mission_id, reason, None, None
        self._on_replaced()

    def start(self, now_us: int, position: Vec3, first_index: int, home: HomePosition | None) -> MissionProgress:
        """Start (or resume, ``first_index`` −1) the loaded mission from ``home``, its geodetic items placed about
        it (:func:`stack.mission.items.about_home`)."""
        assert self.mission is not None and self.tracker is not None
        if home is not None and home.global_valid and self.mission.home is not None:
            placed = about_home(self.mission, GeoPoint(home.lat, home.lon, home.alt))
            if placed is not self.mission:
                self.mission = placed
                self.tracker.replace_items(placed)
        return self.tracker.start(now_us, position, first_index, home.position if home is not None else ZERO3)

    def set_params(self, params: Mapping[str, object]) -> None:
        if self.tracker is not None:
            self.tracker.set_params(params)

    def status(self) -> MissionStatus:
        if self.tracker is None or self.mission is None:
            return MissionStatus(self.mission_id, False, self.reason, 0, 0, -1, False)
        progress = self.tracker.progress
        return MissionStatus(
            self.mission_id, True, "", progress.seq_total, progress.seq_current, progress.seq_reached, progress.finished
        )


class MissionResultPublisher:
    """Module glue shared by the navigators: decode each upload, hand it over, and publish ``mission_result``
    when the status changes and every MISSION_RESULT_REPUBLISH_US."""

    def __init__(
        self,
        load: Callable[[Mission, int], str],
        refuse: Callable[[int, str], None],
        status: Callable[[], MissionStatus],
    ) -> None:
        self._load, self._refuse, self._status = load, refuse, status
        self._published: MissionStatus | None = None
        self._published_us = 0

    def take_uploads(self, module: Module) -> None:
        """Load every upload the module received on ``mission``, logging each verdict."""
        for upload in module.take(ORB_ID.mission):
            problem = self.upload(upload)
            if problem:
                module.reject(f"mission {upload.mission_id}: {problem}")
            else:
                module.log.info("mission %d accepted: %d items", upload.mission_id, len(upload.items))

    def publish_result(self, module: Module, now_us: int) -> None:
        result = self.result(now_us)
        if result is not None:
            module.publish(ORB_ID.mission_result, result)

    def upload(self, upload: navigation.Mission) -> str:
        """Load one ``mission`` message; returns the refusal ("" when accepted)."""
        try:
            mission = mission_from_message(upload)
        except ValueError as e:
            problem = f"malformed mission: {e}"
            self._refuse(upload.mission_id, problem)
        else:
            problem = self._load(mission, upload.mission_id)
        self._published = None
        return problem

    def result(self, now_us: int) -> navigation.MissionResult | None:
        """The ``mission_result`` to publish now, if one is due."""
        status = self._status()
        if status == self._published and now_us - self._published_us < MISSION_RESULT_REPUBLISH_US:
            return None
        self._published, self._published_us = status, now_us
        return navigation.MissionResult(
            timestamp=now_us,
            mission_id=status.mission_id,
            seq_reached=status.seq_reached,
            seq_current=status.seq_current,
            seq_total=status.seq_total,
            valid=status.valid,
            finished=status.finished,
            failure=not status.valid and bool(status.reason),
            reason=status.reason,
        )
