"""The control chain the commander watches: the estimators and controllers whose loss is a failsafe.

Every module in the chain publishes an output each control cycle while its loop runs, so that output is its
heartbeat at the control rate: a module whose output stopped for SILENCE_US while the loop should run is
*silent* (measured against the chain's newest output, so that a simulator or bus that pauses the whole chain
silences no module, and from the chain's resumption after such a pause: its outputs then come back in the chain's
order, the rate loop's before the attitude loop's); one whose process is gone (its liveliness token withdrawn, see
the commander's glue) is *dead*, known at once. PX4 runs these loops in one process and has no such failure; its
matching actions are those of the estimate and control failures (``src/modules/commander/failsafe/failsafe.cpp``):

* losing an attitude estimate, attitude, rate control or the allocator is a loss of **attitude control**:
  flight termination in the air, disarm on the ground;
* losing the position estimate, the flight mode manager or the position controller is a loss of **position
  control**: land (descend if the position estimate is gone too).

A fixed-wing vehicle's chain (:data:`FW_CHAIN`, watched instead when MAV_TYPE makes the vehicle a plane) is
the estimators, the airspeed selector (``airspeed_validated``), the navigator (``position_setpoint_triplet``,
in the auto modes but Descend), fw_pos_control (``vehicle_attitude_setpoint``, in the modes with a position or altitude
loop), fw_att_control (``vehicle_torque_setpoint``, while the rate loop runs) and the allocator; losing the
navigator or fw_pos_control is a loss of position control (the failsafe then descends), losing the airspeed
only a warning. The navigator publishes at 20 Hz and the airspeed selector at 10 Hz, as PX4's do: their silence
and lateness limits are those of a 50 Hz loop stretched by the same factor.

On the RotorS profiles RotorS' controller (roll_pitch_yawrate_thrust_controller) stands in for attitude and rate
control and the allocator, and its joystick interface maps the sticks in the RotorS mode: losing either is a
loss of attitude control too.

A module is watched only once its output has been seen since the stack started (a profile without it, e.g. an
external autopilot's, never flags it), only while armed, and only while the control mode runs its loop; a loop
that has just been switched on gets the silence limit to speak. Once the modules running have been reported, only
theirs are watched: the RotorS controller publishes the allocator's ``actuator_motors``, and an Offboard rate
setpoint is mc_att_control's ``vehicle_rates_setpoint``, on profiles that run neither module. Before any report,
of the modules that share an output only the first is watched. In Offboard the setpoints (position, attitude or rates)
come from outside and their loss is the Offboard failsafe, so only the estimators, rate control and the
allocator are watched there.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from enum import IntEnum

from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleControlMode
from stack.msg.topic import Topic

SILENCE_US = 90_000
"""In lockstep, an output this much older than the newest output of the chain, while its loop should run, names
its module silent: with the commander at 100 Hz, a silent module is noticed within 100 ms of simulated time."""
REALTIME_SILENCE_US = 500_000
"""The same in real time, where a process of a loaded machine is now and then not scheduled for 0.1 s: a dead
module is known at once from its liveliness, a hung one after this."""


STALE_US = 30_000
"""An output older than this (more than the slowest loop's period, 20 ms) is late: the commander then sends its
state at once and on every cycle, so that a module restarted after a crash, which knows nothing yet, learns the
control mode and the land state long before it would count as silent."""


PAUSE_US = 100_000
"""No output of the chain for this long is a pause of the whole chain (a stalled bus or machine, in real time): each
module then gets the silence limit to speak again from the first output after it. In lockstep the chain never
pauses in simulated time."""


CONTROL_PERIOD_US = 20_000
"""The period of the chain's 50 Hz loops, which SILENCE_US and STALE_US are sized for."""


class Loss(IntEnum):
    """What a module's loss costs, least severe first."""

    NONE = 0
    AIRSPEED = 1
    POSITION_CONTROL = 2
    ATTITUDE_CONTROL = 3


@dataclass(frozen=True)
class ChainLink:
    module: str
    output: Topic
    loss: Loss
    runs: Callable[[VehicleControlMode], bool]
    """Whether the control mode runs this module's loop (it is only watched while armed)."""
    period_us: int = CONTROL_PERIOD_US
    """How often the module publishes its output; a slower one's silence and lateness limits stretch alike."""


def _always(mode: VehicleControlMode) -> bool:
    return True


def _position_control(mode: VehicleControlMode) -> bool:
    return mode.flag_multicopter_position_control_enabled and not mode.flag_control_offboard_enabled


def _attitude_control(mode: VehicleControlMode) -> bool:
    return mode.flag_control_attitude_enabled and not mode.flag_control_offboard_enabled


def _rate_control(mode: VehicleControlMode) -> bool:
    return mode.flag_control_rates_enabled


def _allocation(mode: VehicleControlMode) -> bool:
    return mode.flag_control_allocation_enabled


def _rotors_sticks(mode: VehicleControlMode) -> bool:
    return mode.flag_control_rpyt_enabled


def _fw_position_control(mode: VehicleControlMode) -> bool:
    loops = (
        mode.flag_control_position_enabled
        or mode.flag_control_velocity_enabled
        or mode.flag_control_altitude_enabled
        or mode.flag_control_climb_rate_enabled
    )
    return loops and not mode.flag_control_offboard_enabled


def _navigation(mode: VehicleControlMode) -> bool:
    """The navigator's modes: the auto modes but Descend, which the position controller flies on its own."""
    return mode.flag_control_auto_enabled and mode.flag_control_position_enabled


CHAIN: tuple[ChainLink, ...] = (
    ChainLink("attitude_estimator_q", ORB_ID.vehicle_attitude, Loss.ATTITUDE_CONTROL, _always),
    ChainLink("local_position_estimator", ORB_ID.vehicle_local_position, Loss.POSITION_CONTROL, _always),
    ChainLink("flight_mode_manager", ORB_ID.trajectory_setpoint, Loss.POSITION_CONTROL, _position_control),
    ChainLink("mc_pos_control", ORB_ID.vehicle_attitude_setpoint, Loss.POSITION_CONTROL, _position_control),
    ChainLink("mc_att_control", ORB_ID.vehicle_rates_setpoint, Loss.ATTITUDE_CONTROL, _attitude_control),
    ChainLink("mc_rate_control", ORB_ID.vehicle_torque_setpoint, Loss.ATTITUDE_CONTROL, _rate_control),
    ChainLink("control_allocator", ORB_ID.actuator_motors, Loss.ATTITUDE_CONTROL, _allocation),
    ChainLink("roll_pitch_yawrate_thrust_controller", ORB_ID.actuator_motors, Loss.ATTITUDE_CONTROL, _allocation),
    ChainLink("rotors_joy_interface", ORB_ID.roll_pitch_yawrate_thrust_setpoint, Loss.ATTITUDE_CONTROL, _rotors_sticks),
)
NAVIGATOR_PERIOD_US = 50_000
"""PX4's navigator runs at 20 Hz."""
AIRSPEED_SELECTOR_PERIOD_US = 100_000
"""PX4's airspeed_selector runs at 10 Hz."""
FW_CHAIN: tuple[ChainLink, ...] = (
    ChainLink("attitude_estimator_q", ORB_ID.vehicle_attitude, Loss.ATTITUDE_CONTROL, _always),
    ChainLink("local_position_estimator", ORB_ID.vehicle_local_position, Loss.POSITION_CONTROL, _always),
    ChainLink("airspeed_selector", ORB_ID.airspeed_validated, Loss.AIRSPEED, _always, AIRSPEED_SELECTOR_PERIOD_US),
    ChainLink("navigator", ORB_ID.position_setpoint_triplet, Loss.POSITION_CONTROL, _navigation, NAVIGATOR_PERIOD_US),
    ChainLink("fw_pos_control", ORB_ID.vehicle_attitude_setpoint, Loss.POSITION_CONTROL, _fw_position_control),
    ChainLink("fw_att_control", ORB_ID.vehicle_torque_setpoint, Loss.ATTITUDE_CONTROL, _rate_control),
    ChainLink("control_allocator", ORB_ID.actuator_motors, Loss.ATTITUDE_CONTROL, _allocation),
)
"""A fixed-wing vehicle's chain."""
OUTPUTS: tuple[Topic, ...] = tuple(dict.fromkeys(link.output for link in CHAIN + FW_CHAIN))
"""Every output either chain watches (the commander's glue reports their arrivals)."""


@dataclass(frozen=True)
class ChainFault:
    module: str
    loss: Loss
    dead: bool

    def describe(self) -> str:
        what = _LOSS_TEXT.get(self.loss, "nothing")
        return f"{self.module} {'dead' if self.dead else 'silent'}: {what} lost"


_LOSS_TEXT = {
    Loss.ATTITUDE_CONTROL: "attitude control",
    Loss.POSITION_CONTROL: "position control",
    Loss.AIRSPEED: "airspeed",
}


class ControlChainMonitor:
    """Which chain modules are dead or silent now (I/O-free: the glue reports outputs and deaths)."""

    def __init__(self, chain: tuple[ChainLink, ...] = CHAIN, silence_us: int = SILENCE_US) -> None:
        self.silence_us = silence_us
        self._seen: dict[Topic, int] = {}
        """Each output's last arrival on the commander's clock (outputs never seen are absent)."""
        self._heard_us: int | None = None
        """The last arrival of any output."""
        self._resumed_us = 0
        """The first arrival after the chain's last pause."""
        self._watch_since: dict[str, int] = {}
        """When each watched module's watch began."""
        self._dead: set[str] = set()
        self._running: set[str] = set()
        """The modules reported running (or dead) so far."""
        self.late = False
        """Whether a watched output was late (older than STALE_US) at the last update."""
        self.use(chain)

    @property
    def chain(self) -> tuple[ChainLink, ...]:
        return self._chain

    def use(self, chain: tuple[ChainLink, ...]) -> None:
        """Watch ``chain`` from now on (the vehicle type changed); what was seen and reported is kept."""
        self._chain = chain
        self._stand_ins = frozenset(
            link.module for i, link in enumerate(chain) if any(other.output == link.output for other in chain[:i])
        )
        """Modules whose output an earlier module of the chain also publishes."""
        self._watch_since.clear()

    def output_seen(self, topic: Topic, now_us: int) -> None:
        if self._heard_us is not None and now_us - self._heard_us > PAUSE_US:
            self._resumed_us = now_us
        self._heard_us = now_us
        self._seen[topic] = now_us

    def last_output_us(self, modules: Collection[str]) -> int | None:
        """The last arrival of an output of the chain's ``modules`` (None: none seen yet)."""
        outputs = {link.output for link in self._chain if link.module in modules}
        return max((t for topic, t in self._seen.items() if topic in outputs), default=None)

    def module_died(self, module: str) -> None:
        self._running.add(module)
        self._dead.add(module)

    def module_alive(self, module: str) -> None:
        self._running.add(module)
        self._dead.discard(module)

    def _watched(self, link: ChainLink) -> bool:
        """Whether the profile runs ``link``'s module, as far as the reports tell."""
        if self._running:
            return link.module in self._running
        return link.module not in self._stand_ins

    def update(self, now_us: int, armed: bool, mode: VehicleControlMode) -> list[ChainFault]:
        """The faults now, attitude-control losses first."""
        faults: list[ChainFault] = []
        self.late = False
        watched: list[tuple[ChainLink, int]] = []
        for link in self._chain:
            if not (armed and link.output in self._seen and link.runs(mode) and self._watched(link)):
                self._watch_since.pop(link.module, None)
                continue
            since = self._watch_since.setdefault(link.module, now_us)
            watched.append((link, max(self._seen[link.output], since, self._resumed_us)))
        newest = max((heard for _, heard in watched), default=now_us)
        for link, heard in watched:
            stretch = max(link.period_us / CONTROL_PERIOD_US, 1.0)
            self.late |= now_us - heard > STALE_US * stretch
            dead = link.module in self._dead
            if dead or newest - heard > self.silence_us * stretch:
                faults.append(ChainFault(link.module, link.loss, dead))
        faults.sort(key=lambda f: -f.loss)
        return faults
