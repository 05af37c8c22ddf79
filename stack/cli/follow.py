"""Following an action for ``stack cmd --wait`` on the vehicle's messages: when it is done, when it failed
(a failsafe took over, the vehicle disarmed or left the action's mode, it is not where asked), what to
print while it goes on, and how long it may take.

The time an action may take is sized to it: the distances to fly at the vehicle's speed and climb-rate
parameters (PX4's MPC_XY_CRUISE, MPC_Z_V_AUTO_UP/DN, MPC_TKO_SPEED, MPC_LAND_SPEED, the return's
RTL_RETURN_ALT/RTL_DESCEND_ALT/RTL_LAND_DELAY and the disarm delay COM_DISARM_LAND), times
:data:`BUDGET_FACTOR`, plus :data:`BUDGET_FLOOR_S` for everything the figures leave out (arming, settling,
a slow machine). The caller counts it in the vehicle's time: simulated seconds in lockstep.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from stack.commander.events import CRITICAL_EVENTS
from stack.commander.modes import mode_name
from stack.fw.runway import on_runway
from stack.mission.items import MAV_CMD_NAV_LAND, MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_CMD_NAV_TAKEOFF, Mission
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.system import HomePosition, MavlinkLog, VehicleStatus

NS = VehicleStatus

BUDGET_FACTOR = 3.0
BUDGET_FLOOR_S = 30.0
REACHED_M = 1.0
"""How close to the asked position (or altitude) counts as there."""

PARAMS = (
    "MPC_XY_CRUISE",
    "MPC_Z_V_AUTO_UP",
    "MPC_Z_V_AUTO_DN",
    "MPC_TKO_SPEED",
    "MPC_LAND_SPEED",
    "COM_DISARM_LAND",
    "MIS_TAKEOFF_ALT",
    "NAV_ACC_RAD",
    "RTL_RETURN_ALT",
    "RTL_DESCEND_ALT",
    "RTL_LAND_DELAY",
)
"""The parameters the budgets and checks read (from the running stack, else their defaults)."""

PROGRESS_HEARTBEAT_S = 10.0
"""An unchanged progress line is printed again after this many wall-clock seconds (the wait is alive)."""

Params = Mapping[str, float]
NED = tuple[float, float, float]


@dataclass
class Vehicle:
    """The latest of what the vehicle said."""

    status: VehicleStatus | None = None
    position: VehicleLocalPosition | None = None
    home: HomePosition | None = None
    mission: MissionResult | None = None
    said: str = ""
    """The commander's latest warning or worse on ``mavlink_log`` (a failsafe's cause, a refusal)."""
    now_us: int = 0
    """The newest timestamp seen: the vehicle's clock (simulated in lockstep)."""

    def update(self, topic: str, msg: object) -> None:
        self.now_us = max(self.now_us, getattr(msg, "timestamp", 0))
        if topic == "vehicle_status":
            self.status = msg  # type: ignore[assignment]
        elif topic == "vehicle_local_position":
            self.position = msg  # type: ignore[assignment]
        elif topic == "home_position":
            self.home = msg  # type: ignore[assignment]
        elif topic == "mission_result":
            self.mission = msg  # type: ignore[assignment]
        elif isinstance(msg, MavlinkLog) and msg.severity <= MavlinkLog.SEVERITY_WARNING:
            self.said = msg.text

    def failsafe_explained(self) -> bool:
        """Whether the commander has said which failsafe it activated."""
        return self.said.startswith(CRITICAL_EVENTS)

    @property
    def armed(self) -> bool:
        return self.status is not None and self.status.arming_state == NS.ARMING_STATE_ARMED

    @property
    def disarmed(self) -> bool:
        return self.status is not None and self.status.arming_state != NS.ARMING_STATE_ARMED

    def home_ned(self) -> NED:
        """Home in local NED (the local origin until the vehicle has one)."""
        if self.home is not None and self.home.valid_lpos:
            return (self.home.x, self.home.y, self.home.z)
        return (0.0, 0.0, 0.0)

    def height(self) -> float:
        """Metres above home (NaN without a position)."""
        return self.home_ned()[2] - self.position.z if self.position is not None else math.nan

    def distance_to(self, target: NED) -> float:
        """Metres to ``target`` (its NaN components left out)."""
        if self.position is None:
            return math.nan
        here = (self.position.x, self.position.y, self.position.z)
        return math.sqrt(sum((t - p) ** 2 for t, p in zip(target, here, strict=True) if not math.isnan(t)))

    def describe(self) -> str:
        """Altitude and mode in words, for progress lines."""
        parts = []
        if self.position is not None:
            parts.append(f"altitude {self.height():.1f} m")
        if self.status is not None:
            parts.append(mode_name(self.status.nav_state) + ("" if self.armed else " (disarmed)"))
        return ", ".join(parts) or "no vehicle state yet"


def budget_s(nominal_s: float) -> float:
    """The time an action nominally taking ``nominal_s`` may take."""
    return BUDGET_FACTOR * max(0.0, nominal_s) + BUDGET_FLOOR_S


def travel_s(horizontal_m: float, climb_m: float, p: Params, speed: float = math.nan) -> float:
    """Time to fly ``horizontal_m`` at ``speed`` (default the cruise speed) and climb ``climb_m`` (negative:
    descend) at the auto climb or descent rate, one after the other."""
    cruise = speed if math.isfinite(speed) and speed > 0 else p["MPC_XY_CRUISE"]
    vertical = climb_m / p["MPC_Z_V_AUTO_UP"] if climb_m > 0 else -climb_m / p["MPC_Z_V_AUTO_DN"]
    return horizontal_m / cruise + vertical


def landing_s(height_m: float, p: Params) -> float:
    """Time to land from ``height_m`` above home at the landing rate and be disarmed on the ground."""
    return max(0.0, height_m) / p["MPC_LAND_SPEED"] + max(0.0, p["COM_DISARM_LAND"])


@dataclass
class Action:
    """One followed action. ``modes``: the navigation states it flies in (leaving them interrupts it);
    ``ends_disarmed``: it is done once the vehicle disarmed on the ground."""

    name: str
    modes: frozenset[int]
    ends_disarmed: bool = False
    p: Params = field(default_factory=dict)

    def nominal_s(self, v: Vehicle) -> float:
        raise NotImplementedError

    def done(self, v: Vehicle) -> str | None:
        raise NotImplementedError

    def progress(self, v: Vehicle) -> str:
        return v.describe()

    def failed(self, v: Vehicle) -> str | None:
        """Why the action cannot complete any more, or None."""
        status = v.status
        if status is None:
            return None
        said = f": {v.said}" if v.said else ""
        if status.failsafe:
            return f"{self.name} failed: a failsafe took over ({mode_name(status.nav_state)}){said}"
        if v.disarmed and not self.ends_disarmed:
            return f"{self.name} failed: the vehicle disarmed{said}"
        if v.armed and status.nav_state not in self.modes:
            return f"{self.name} interrupted: now in {mode_name(status.nav_state)}"
        return None


@dataclass
class Takeoff(Action):
    height_m: float = math.nan
    """Metres above home asked (NaN: MIS_TAKEOFF_ALT)."""

    def target(self) -> float:
        return self.height_m if math.isfinite(self.height_m) else self.p["MIS_TAKEOFF_ALT"]

    def nominal_s(self, v: Vehicle) -> float:
        height = v.height() if math.isfinite(v.height()) else 0.0
        return (self.target() - height) / self.p["MPC_TKO_SPEED"]

    def done(self, v: Vehicle) -> str | None:
        # Done in the Hold that follows the takeoff, at the altitude: Hold comes before the climb ends (PX4's
        # navigator), and a failsafe may hold the vehicle on the ground.
        if v.status is None or v.status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
            return None
        if not abs(v.height() - self.target()) <= REACHED_M:
            return None
        return f"{self.name} complete: {v.describe()}"

    def progress(self, v: Vehicle) -> str:
        return f"{v.describe()} of {self.target():.1f} m"


@dataclass
class Goto(Action):
    target: Callable[[VehicleLocalPosition], NED] = lambda _: (math.nan, math.nan, math.nan)
    speed: float = math.nan

    def _target(self, v: Vehicle) -> NED | None:
        return self.target(v.position) if v.position is not None else None

    def nominal_s(self, v: Vehicle) -> float:
        target, here = self._target(v), v.position
        if target is None or here is None:
            return 0.0
        north, east = (t if math.isfinite(t) else h for t, h in zip(target[:2], (here.x, here.y), strict=True))
        horizontal = math.hypot(north - here.x, east - here.y)
        return travel_s(horizontal, here.z - target[2] if math.isfinite(target[2]) else 0.0, self.p, self.speed)

    def distance(self, v: Vehicle) -> float:
        target = self._target(v)
        return v.distance_to(target) if target is not None else math.nan

    def done(self, v: Vehicle) -> str | None:
        if v.status is None or not self.distance(v) <= REACHED_M:
            return None
        return f"{self.name}: reached ({v.describe()})"

    def progress(self, v: Vehicle) -> str:
        return f"{self.distance(v):.1f} m to go, {v.describe()}"


@dataclass
class Land(Action):
    def nominal_s(self, v: Vehicle) -> float:
        return landing_s(v.height(), self.p) if math.isfinite(v.height()) else 0.0

    def done(self, v: Vehicle) -> str | None:
        if not v.disarmed:
            return None
        return f"{self.name}: landed and disarmed"


@dataclass
class Return(Action):
    def nominal_s(self, v: Vehicle) -> float:
        if v.position is None:
            return 0.0
        p, height = self.p, v.height()
        home = v.home_ned()
        distance = math.hypot(v.position.x - home[0], v.position.y - home[1])
        top = max(height, p["RTL_RETURN_ALT"])
        descend = travel_s(0.0, -(top - min(top, p["RTL_DESCEND_ALT"])), p)
        delay = max(0.0, p["RTL_LAND_DELAY"])
        return travel_s(distance, top - height, p) + descend + delay + landing_s(min(top, p["RTL_DESCEND_ALT"]), p)

    def done(self, v: Vehicle) -> str | None:
        landed = self._landed(v)
        return None if landed is None or not landed[0] else f"{self.name}: {landed[1]} and disarmed"

    def failed(self, v: Vehicle) -> str | None:
        landed = self._landed(v)
        if landed is not None and not landed[0]:
            return f"{self.name} failed: disarmed {landed[1]}"
        return super().failed(v)

    def _landed(self, v: Vehicle) -> tuple[bool, str] | None:
        """Once disarmed: whether where the vehicle rests is where a return lands, and where that is. A
        multicopter lands at home; a plane lands along the runway it took off from (home, on the heading it
        armed with), and rolls out along it."""
        if not v.disarmed or v.position is None:
            return None
        home = v.home_ned()
        if v.status is not None and v.status.vehicle_type == NS.VEHICLE_TYPE_FIXED_WING:
            heading = v.home.yaw if v.home is not None else 0.0
            ok, along, across = on_runway((v.position.x, v.position.y), (home[0], home[1]), heading)
            where = f"{along:.0f} m along the runway, {abs(across):.1f} m off its centre line"
            return ok, f"landed on the runway ({where})" if ok else f"off the runway ({where})"
        off = math.hypot(v.position.x - home[0], v.position.y - home[1])
        if off > max(self.p["NAV_ACC_RAD"], REACHED_M):
            return False, f"{off:.1f} m from home"
        return True, f"landed at home ({off:.1f} m off)"


@dataclass
class MissionRun(Action):
    mission: Mission | None = None
    mission_id: int = 0
    started_us: int = 0
    """The start's acknowledgement time: only results published after it count."""

    @property
    def lands(self) -> bool:
        items = self.mission.items if self.mission is not None else ()
        return bool(items) and items[-1].command in (MAV_CMD_NAV_LAND, MAV_CMD_NAV_RETURN_TO_LAUNCH)

    def _result(self, v: Vehicle) -> MissionResult | None:
        m = v.mission
        return m if m is not None and m.mission_id == self.mission_id and m.timestamp > self.started_us else None

    def nominal_s(self, v: Vehicle) -> float:
        if self.mission is None or v.position is None:
            return 0.0
        home = v.home_ned()
        here = [v.position.x - home[0], v.position.y - home[1], v.position.z - home[2]]
        total, speed = 0.0, math.nan
        for item in self.mission:
            speed = item.speed if math.isfinite(item.speed) else speed
            there = [t if math.isfinite(t) else h for t, h in zip(item.position, here, strict=True)]
            if item.command == MAV_CMD_NAV_TAKEOFF:
                total += max(0.0, here[2] - there[2]) / self.p["MPC_TKO_SPEED"]
            elif item.command == MAV_CMD_NAV_RETURN_TO_LAUNCH:
                there = [0.0, 0.0, min(here[2], -self.p["RTL_RETURN_ALT"])]
                total += travel_s(math.hypot(here[0], here[1]), here[2] - there[2], self.p, speed)
                total += landing_s(-there[2], self.p)
                there[2] = 0.0
            elif item.command == MAV_CMD_NAV_LAND:
                total += travel_s(math.hypot(there[0] - here[0], there[1] - here[1]), 0.0, self.p, speed)
                total += landing_s(-here[2], self.p)
                there[2] = 0.0
            else:
                total += travel_s(math.hypot(there[0] - here[0], there[1] - here[1]), here[2] - there[2], self.p, speed)
            total += item.hold_time
            here = there
        return total

    def done(self, v: Vehicle) -> str | None:
        result = self._result(v)
        if result is None or not result.finished:
            return None
        if not self.lands:
            return f"{self.name} finished"
        return f"{self.name} finished, landed and disarmed" if v.disarmed else None

    def failed(self, v: Vehicle) -> str | None:
        result = self._result(v)
        if result is not None and result.failure:
            return f"{self.name} failed: {result.reason or f'at item {result.seq_current + 1}'}"
        finished = result is not None and result.finished
        if finished and self.lands:
            # Landing after the last item, in whatever mode the navigator lands in.
            return super().failed(v) if v.status is not None and v.status.failsafe else None
        if finished:
            return None
        if v.disarmed:
            said = f": {v.said}" if v.said else ""
            return f"{self.name} failed: the vehicle disarmed before the end of the mission{said}"
        return super().failed(v)

    def progress(self, v: Vehicle) -> str:
        result = self._result(v)
        item = f"item {result.seq_current + 1}/{result.seq_total}, " if result is not None else ""
        return item + v.describe()


TAKEOFF_MODES = frozenset((NS.NAVIGATION_STATE_AUTO_TAKEOFF, NS.NAVIGATION_STATE_AUTO_LOITER))
GOTO_MODES = frozenset((NS.NAVIGATION_STATE_AUTO_LOITER,))
LAND_MODES = frozenset((NS.NAVIGATION_STATE_AUTO_LAND,))
RETURN_MODES = frozenset((NS.NAVIGATION_STATE_AUTO_RTL, NS.NAVIGATION_STATE_AUTO_LAND))
MISSION_MODES = frozenset((NS.NAVIGATION_STATE_AUTO_MISSION,))


class Progress:
    """Which progress lines ``--wait`` prints: a changed one at once, an unchanged one every PROGRESS_HEARTBEAT_S."""

    def __init__(self, heartbeat_s: float = PROGRESS_HEARTBEAT_S) -> None:
        self.heartbeat_s = heartbeat_s
        self.line = ""
        self._printed_at = -math.inf

    def due(self, line: str, now_s: float) -> bool:
        """Whether ``line`` (the progress at wall time ``now_s``) is to be printed; it is ``line`` then."""
        if line == self.line and now_s - self._printed_at < self.heartbeat_s:
            return False
        self.line, self._printed_at = line, now_s
        return True
