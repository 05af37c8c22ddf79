"""The control chain the commander watches: the estimators and controllers whose loss is a failsafe.

Every module in the chain publishes an output each control cycle while its loop runs, so that output is its
heartbeat at the control rate: a module whose output stopped for SILENCE_US while the loop should run is
*silent* (measured against the chain's newest output, so that a simulator or bus that pauses the whole chain
silences no module); one whose process is gone (its liveliness token withdrawn, see the commander's glue) is
*dead*, known at once. PX4 runs these loops in one process and has no such failure; its matching actions are
those of the estimate and control failures (``src/modules/commander/failsafe/failsafe.cpp``):

* losing an attitude estimate, attitude, rate control or the allocator is a loss of **attitude control**:
  flight termination in the air, disarm on the ground;
* losing the position estimate, the flight mode manager or the position controller is a loss of **position
  control**: land (descend if the position estimate is gone too).

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

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum

from stack.msg.system import VehicleControlMode

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


class Loss(IntEnum):
    NONE = 0
    POSITION_CONTROL = 1
    ATTITUDE_CONTROL = 2


@dataclass(frozen=True)
class ChainLink:
    module: str
    output: str
    loss: Loss
    runs: Callable[[VehicleControlMode], bool]
    """Whether the control mode runs this module's loop (it is only watched while armed)."""


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


CHAIN: tuple[ChainLink, ...] = (
    ChainLink("attitude_estimator_q", "vehicle_attitude", Loss.ATTITUDE_CONTROL, _always),
    ChainLink("local_position_estimator", "vehicle_local_position", Loss.POSITION_CONTROL, _always),
    ChainLink("flight_mode_manager", "trajectory_setpoint", Loss.POSITION_CONTROL, _position_control),
    ChainLink("mc_pos_control", "vehicle_attitude_setpoint", Loss.POSITION_CONTROL, _position_control),
    ChainLink("mc_att_control", "vehicle_rates_setpoint", Loss.ATTITUDE_CONTROL, _attitude_control),
    ChainLink("mc_rate_control", "vehicle_torque_setpoint", Loss.ATTITUDE_CONTROL, _rate_control),
    ChainLink("control_allocator", "actuator_motors", Loss.ATTITUDE_CONTROL, _allocation),
    ChainLink("roll_pitch_yawrate_thrust_controller", "actuator_motors", Loss.ATTITUDE_CONTROL, _allocation),
    ChainLink("rotors_joy_interface", "roll_pitch_yawrate_thrust_setpoint", Loss.ATTITUDE_CONTROL, _rotors_sticks),
)
OUTPUTS: tuple[str, ...] = tuple(dict.fromkeys(link.output for link in CHAIN))


@dataclass(frozen=True)
class ChainFault:
    module: str
    loss: Loss
    dead: bool

    def describe(self) -> str:
        what = "attitude" if self.loss == Loss.ATTITUDE_CONTROL else "position"
        return f"{self.module} {'dead' if self.dead else 'silent'}: {what} control lost"


class ControlChainMonitor:
    """Which chain modules are dead or silent now (I/O-free: the glue reports outputs and deaths)."""

    def __init__(self, chain: tuple[ChainLink, ...] = CHAIN, silence_us: int = SILENCE_US) -> None:
        self._chain = chain
        self._stand_ins = frozenset(
            link.module for i, link in enumerate(chain) if any(other.output == link.output for other in chain[:i])
        )
        """Modules whose output an earlier module of the chain also publishes."""
        self.silence_us = silence_us
        self._seen: dict[str, int] = {}
        """Each output's last arrival on the commander's clock (outputs never seen are absent)."""
        self._watch_since: dict[str, int] = {}
        """When each watched module's watch began."""
        self._dead: set[str] = set()
        self._running: set[str] = set()
        """The modules reported running (or dead) so far."""
        self.late = False
        """Whether a watched output was late (older than STALE_US) at the last update."""

    def output_seen(self, topic: str, now_us: int) -> None:
        self._seen[topic] = now_us

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
            watched.append((link, max(self._seen[link.output], since)))
        newest = max((heard for _, heard in watched), default=now_us)
        for link, heard in watched:
            self.late |= now_us - heard > STALE_US
            dead = link.module in self._dead
            if dead or newest - heard > self.silence_us:
                faults.append(ChainFault(link.module, link.loss, dead))
        faults.sort(key=lambda f: -f.loss)
        return faults
