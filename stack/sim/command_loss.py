"""The plant's own autopilot for when the flight stack's motor commands stop: PX4's Offboard-loss failsafe.

Split across hosts (the simulator and the estimators on one, the flight controllers and the commander on
another), losing the flight-control host leaves the plant without motor commands. A real vehicle here would be a
Pixhawk whose companion went silent, and PX4 flies it down; so does the plant. :class:`CommandLossFailsafe` is
the simulated Pixhawk's autopilot (``stack.pixhawk_sim``: its commander ``Px4Commander``, PX4's
``MulticopterLandDetector`` at 50 Hz and its control chain ``FlightControl``, wired as ``SimulatedPixhawk.step``
wires them), with the flight stack as its Offboard companion:

* The stack's ``actuator_armed`` arming the motors (armed, and neither lockdown, kill nor termination) arms the
  plant's commander in Offboard, home where the vehicle is, as a companion arms a Pixhawk. Each new
  ``actuator_outputs_sim`` is the Offboard signal's proof of life, and so is that arming: a stack that only just
  armed is not silent.
* While the commands flow they drive the motors unchanged, and nothing else runs.
* Silent for more than COM_OF_LOSS_T of simulated time, the plant's autopilot takes over as PX4 does on Offboard
  loss (``src/modules/commander/HealthAndArmingChecks/checks/offboardCheck.cpp`` raises
  ``offboard_control_signal_lost``; ``src/modules/commander/failsafe/failsafe.cpp``, ``Failsafe::checkStateAndMode``,
  flies ``fromOffboardLossActParam(COM_OBL_RC_ACT)``): Land, Hold (Position, Altitude and Stabilized fall back to
  Hold without RC), Terminate (motors stopped) or Disarm. It flies on the simulator's truth and IMU, from fresh
  loops (a parameter change reaches the loops at the next takeover, the commander and land detector at once).
* Commands again while it flies the failsafe: control returns to the stack at once (PX4 clears the mode fallback
  when the signal returns).
* Landed, it disarms after COM_DISARM_LAND (``Commander::checkForAutoDisarm``) and its motors stop. They stay
  stopped until the stack's ``actuator_armed`` disarms (or stops the motors): then the stack's commands drive
  again, and a new arming arms the plant's commander again. A stack that says disarmed while the plant still flies
  its failsafe (restarted after its host was lost, it knows nothing of the flight) does not stop it: the plant
  lands first. Lockdown, kill and termination stop the motors at once.

Only a multicopter (:class:`~stack.airframe.model.VehicleModel`) has one: for a fixed-wing or a JSBSim plant the
simulator makes no takeover and keeps applying the last commands. The parameters are the simulator module's, with
the vehicle model's ``[airframe]`` table over them: the geometry the allocator flies is the plant's own, as the
simulated Pixhawk takes it.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from enum import Enum

from stack.airframe.model import VehicleModel
from stack.commander import land_detector
from stack.commander.home import HomePosition
from stack.commander.land_detector import MulticopterLandDetector
from stack.commander.offboard import OffboardLossAction
from stack.mathlib import quaternion as quat
from stack.mavlink.px4_modes import Px4Mode, name
from stack.msg.system import ActuatorArmed
from stack.params.param import Param
from stack.pixhawk_sim.commander import Condition, Px4Commander
from stack.pixhawk_sim.flight import FlightControl, VehicleState
from stack.pixhawk_sim.params import AUTOPILOT_PARAMS
from stack.pixhawk_sim.vehicle import condition, home_here, land_detector_inputs
from stack.sim.sensors import ImuSample
from stack.sim.simulator import GroundTruth

PARAMS: tuple[Param, ...] = AUTOPILOT_PARAMS
_NAMES = frozenset(p.name for p in PARAMS)

_ACTIONS = {
    Px4Mode.AUTO_LAND: "lands",
    Px4Mode.AUTO_LOITER: "holds its position",
    Px4Mode.TERMINATION: "stops its motors (flight termination)",
}
"""What the plant does in the failsafe's mode, for the log."""


class MotorControl(Enum):
    """Who drives the motors."""

    STACK = "stack"
    """The flight stack's commands (also while disarmed: they are then stopped)."""
    FAILSAFE = "failsafe"
    """The plant's autopilot, flying COM_OBL_RC_ACT."""
    DISARMED = "disarmed"
    """The plant's autopilot disarmed itself: motors stopped until the flight stack disarms."""


class CommandLossFailsafe:
    """See the module docstring. ``motor_commands`` once per IMU step, before the physics advance."""

    def __init__(self, params: Mapping[str, object], model: VehicleModel, imu_period_us: int) -> None:
        self._airframe = {k: v for k, v in model.airframe.items() if k in _NAMES}
        self._period_us = imu_period_us
        self._land_detector_every = land_detector.PERIOD_US // imu_period_us
        self._stopped = (0.0,) * model.rotor_count
        self.control = MotorControl.STACK
        self.events: list[tuple[int, str]] = []
        """Log records (level, text) of the changes of control, for the caller to take."""
        self._commander: Px4Commander | None = None
        self._flight: FlightControl | None = None
        self._land: MulticopterLandDetector | None = None
        self._home: HomePosition | None = None
        self._tick = 0
        self._takeover_us = 0
        self.set_params(params)

    def set_params(self, params: Mapping[str, object]) -> None:
        self._params = {**{k: params[k] for k in _NAMES}, **self._airframe}
        self._loss_timeout_s = float(self._params["COM_OF_LOSS_T"])
        if self._commander is not None:
            self._commander.set_params(self._params)
        if self._land is not None:
            self._land.set_params(self._params)

    @property
    def mode(self) -> Px4Mode | None:
        """The mode the plant's autopilot flies (PX4's ``nav_state``), None while the stack has not armed."""
        return self._commander.mode if self._commander is not None else None

    def take_events(self) -> list[tuple[int, str]]:
        events, self.events = self.events, []
        return events

    def motor_commands(
        self,
        now_us: int,
        outputs_arrived: bool,
        armed: ActuatorArmed | None,
        truth: GroundTruth,
        imu: ImuSample | None,
        commands: tuple[float, ...],
    ) -> tuple[float, ...]:
        """The motor commands to apply for the next step.

        ``now_us``: the simulator's time; ``outputs_arrived``: a new ``actuator_outputs_sim`` this step;
        ``armed``: the last ``actuator_armed`` (None: none yet); ``truth`` and ``imu``: the plant's state and its
        last IMU sample (None before the first); ``commands``: what the stack's last outputs command now."""
        stopped = armed is not None and (armed.lockdown or armed.kill or armed.termination)
        if armed is None or not armed.armed or stopped:
            if self._flying_failsafe() and not stopped and imu is not None:
                # A stack restarted after its host was lost knows nothing of the flight and says disarmed: the plant
                # in the air flies on (a Pixhawk disarms on a command, never on its companion's silence or restart).
                return self._fly_on(now_us, truth, imu)
            if self._commander is not None:
                self._stand_down()
            return commands
        if imu is None:  # before the simulator's first step: nothing to fly on
            return commands
        commander = self._commander or self._arm(now_us, truth)
        if outputs_arrived:
            commander.offboard_setpoint(now_us)
        taking_over = self.control is MotorControl.STACK
        if taking_over:
            if commander.offboard_signal(now_us):
                return commands
            self._take_over(now_us, truth)
        elif self.control is MotorControl.DISARMED:
            return self._stopped
        elif outputs_arrived:
            # The signal is back: PX4's commander flies the user's Offboard again (unless terminated).
            commander.set_mode(Px4Mode.OFFBOARD, now_us)
            commander.take_notices()
            if commander.mode is Px4Mode.OFFBOARD:
                self._hand_back(now_us)
                return commands
        motors = self._fly(now_us, truth, imu)
        if taking_over:
            self._announce_takeover(commander)
        return self._unless_disarmed(motors)

    def _flying_failsafe(self) -> bool:
        return self.control is MotorControl.FAILSAFE and self._land is not None and not self._land.state.landed

    def _fly_on(self, now_us: int, truth: GroundTruth, imu: ImuSample) -> tuple[float, ...]:
        return self._unless_disarmed(self._fly(now_us, truth, imu))

    def _unless_disarmed(self, motors: tuple[float, ...]) -> tuple[float, ...]:
        """The failsafe's motor commands, or stopped motors once the plant's commander has disarmed."""
        assert self._commander is not None
        if not self._commander.armed:
            self._disarmed(self._commander)
            return self._stopped
        return motors

    def status(self) -> dict[str, str]:
        """Who drives the motors and, while the plant does, the mode it flies."""
        mode = self.mode
        flying = self.control is MotorControl.FAILSAFE and mode is not None
        return {"motor_control": self.control.value, "plant_mode": name(mode) if flying else ""}

    def _arm(self, now_us: int, truth: GroundTruth) -> Px4Commander:
        """The stack armed: the plant's commander arms in Offboard (forced: the stack made the arming checks)."""
        commander = self._commander = Px4Commander(self._params)
        commander.set_mode(Px4Mode.OFFBOARD, now_us)
        commander.offboard_setpoint(now_us)
        roll, pitch, _ = quat.to_euler(truth.q)
        commander.arm_disarm(True, True, now_us, Condition(truth.on_ground, truth.on_ground, roll, pitch))
        commander.take_notices()  # PX4's STATUSTEXT: nobody reads the plant's
        self._home = home_here(truth)
        return commander

    def _take_over(self, now_us: int, truth: GroundTruth) -> None:
        self._flight = FlightControl(self._params, self._period_us)
        self._land = MulticopterLandDetector(self._params)
        if not truth.on_ground:
            self._land.resume_in_air()
        self._tick = 0
        self._takeover_us = now_us
        self.control = MotorControl.FAILSAFE

    def _fly(self, now_us: int, truth: GroundTruth, imu: ImuSample) -> tuple[float, ...]:
        commander, flight, land = self._commander, self._flight, self._land
        assert commander is not None and flight is not None and land is not None and self._home is not None
        if self._tick == 0:
            land.update(now_us, land_detector_inputs(now_us, truth, imu, commander, flight))
            commander.update(now_us, condition(land.state, truth))
            commander.take_notices()
        self._tick = (self._tick + 1) % self._land_detector_every
        state = VehicleState(now_us, truth.position, truth.velocity, truth.q, self._home)
        out = flight.update(
            imu.time_us,
            imu.gyro,
            state,
            mode=commander.mode,
            armed=commander.armed,
            landed=land.state.landed,
            maybe_landed=land.state.maybe_landed,
            setpoint=None,
        )
        return out.motors

    def _announce_takeover(self, commander: Px4Commander) -> None:
        action = _ACTIONS[commander.mode] if commander.armed else "disarms"
        self.events.append((
            logging.WARNING,
            f"no motor commands from the flight stack for {self._loss_timeout_s:.1f} s (COM_OF_LOSS_T): the plant "
            f"{action} on its own, as a Pixhawk on Offboard loss (COM_OBL_RC_ACT {self._params['COM_OBL_RC_ACT']})",
        ))

    def _hand_back(self, now_us: int) -> None:
        self.control = MotorControl.STACK
        self._flight = self._land = None
        self.events.append((
            logging.INFO,
            f"motor commands from the flight stack again, {(now_us - self._takeover_us) * 1e-6:.1f} s into the "
            "failsafe: control returns to it",
        ))

    def _disarmed(self, commander: Px4Commander) -> None:
        self.control = MotorControl.DISARMED
        self._flight = self._land = None
        if self._params["COM_OBL_RC_ACT"] == OffboardLossAction.DISARM:
            why = "COM_OBL_RC_ACT Disarm"
        elif commander.have_taken_off:
            why = "landed, COM_DISARM_LAND"
        else:
            why = "no takeoff, COM_DISARM_PRFLT"
        self.events.append((
            logging.INFO,
            f"the plant disarmed itself ({why}): its motors stay stopped until the flight stack disarms",
        ))

    def _stand_down(self) -> None:
        """The stack disarmed or stopped its motors: its commands drive again, and the plant's autopilot rests."""
        if self.control is not MotorControl.STACK:
            self.events.append((
                logging.INFO,
                "the flight stack disarmed (or stopped its motors): its motor commands drive the plant again",
            ))
        self.control = MotorControl.STACK
        self._commander = None
        self._flight = self._land = None
