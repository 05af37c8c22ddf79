"""The plant's own autopilot when the flight stack's motor commands stop: PX4's Offboard-loss failsafe on the
simulated multicopter (PX4 src/modules/commander/failsafe/failsafe.cpp, COM_OF_LOSS_T then COM_OBL_RC_ACT)."""

from __future__ import annotations

import logging

import pytest

from stack.commander.offboard import OffboardLossAction
from stack.msg.system import ActuatorArmed
from stack.sim import command_loss
from stack.sim.command_loss import CommandLossFailsafe, MotorControl
from stack.sim.sensors import ImuSample
from stack.sim.simulator import Simulator

S = 1_000_000
ARMED = ActuatorArmed(armed=True)
DISARMED = ActuatorArmed(armed=False)
LAND = {"COM_OBL_RC_ACT": int(OffboardLossAction.LAND)}


class Plant:
    """The default quad and its takeover, stepped as the simulator module steps them."""

    def __init__(self, **params: object) -> None:
        self.sim = Simulator(seed=1)
        values = {p.name: p.default for p in command_loss.PARAMS} | params
        self.failsafe = CommandLossFailsafe(values, self.sim.model, self.sim.imu_period_us)
        self.truth = self.sim.truth()
        self.imu: ImuSample | None = None
        self.hover = (self.sim.model.hover_command,) * self.sim.model.rotor_count

    def hovering(self, altitude: float = 10.0) -> None:
        self.sim.reset_pose((0.0, 0.0, -altitude), motor_states=self.hover)

    def step(self, arrived: bool, armed: ActuatorArmed | None, commands: tuple[float, ...]) -> tuple[float, ...]:
        motors = self.failsafe.motor_commands(self.sim.time_us, arrived, armed, self.truth, self.imu, commands)
        for sample in self.sim.advance(motors):
            if isinstance(sample, ImuSample):
                self.imu = sample
        self.truth = self.sim.truth()
        return motors

    def run(self, seconds: float, arrived: bool, armed: ActuatorArmed | None, commands: tuple[float, ...]) -> None:
        for _ in range(round(seconds * S / self.sim.imu_period_us)):
            self.step(arrived, armed, commands)

    @property
    def control(self) -> MotorControl:
        return self.failsafe.control


def test_while_the_commands_flow_they_drive_the_motors_unchanged() -> None:
    plant = Plant(**LAND)
    plant.hovering()
    for i in range(5 * S // plant.sim.imu_period_us):
        commands = tuple(c + 1e-4 * ((i + k) % 3) for k, c in enumerate(plant.hover))
        assert plant.step(True, ARMED, commands) is commands
    assert plant.control is MotorControl.STACK and plant.failsafe.events == []
    assert plant.failsafe.status() == {"motor_control": "stack", "plant_mode": ""}


STOPPED = [ActuatorArmed(armed=True, kill=True), ActuatorArmed(armed=True, lockdown=True),
           ActuatorArmed(armed=True, termination=True)]


@pytest.mark.parametrize("armed", [None, DISARMED, *STOPPED])
def test_disarmed_never_armed_or_stopped_by_the_stack_nothing_happens(armed: ActuatorArmed | None) -> None:
    plant = Plant()
    zeros = (0.0,) * 4
    for _ in range(3 * S // plant.sim.imu_period_us):
        assert plant.step(False, armed, zeros) is zeros
    assert plant.control is MotorControl.STACK and plant.failsafe.events == [] and plant.failsafe.mode is None


def test_silence_while_armed_longer_than_com_of_loss_t_takes_over() -> None:
    plant = Plant(**LAND)
    plant.hovering()
    plant.run(0.5, True, ARMED, plant.hover)
    last_output = plant.sim.time_us - plant.sim.imu_period_us
    while plant.sim.time_us - last_output <= S:
        assert plant.step(False, ARMED, plant.hover) == plant.hover
        assert plant.control is MotorControl.STACK
    assert plant.step(False, ARMED, plant.hover) != plant.hover
    assert plant.control is MotorControl.FAILSAFE
    assert plant.failsafe.status() == {"motor_control": "failsafe", "plant_mode": "AUTO.LAND"}
    [(level, text)] = plant.failsafe.take_events()
    assert level == logging.WARNING
    assert text.startswith("no motor commands from the flight stack for 1.0 s (COM_OF_LOSS_T): the plant lands")


def test_silence_counts_from_arming_when_the_last_output_is_older() -> None:
    plant = Plant(COM_OF_LOSS_T=0.5)
    plant.run(2.0, True, DISARMED, (0.0,) * 4)  # the stack's outputs while disarmed, then they stop
    plant.run(2.0, False, DISARMED, (0.0,) * 4)
    armed_at = plant.sim.time_us
    while plant.sim.time_us - armed_at <= S // 2:
        plant.step(False, ARMED, (0.0,) * 4)
        assert plant.control is MotorControl.STACK
    plant.step(False, ARMED, (0.0,) * 4)
    assert plant.control is MotorControl.FAILSAFE
    assert plant.failsafe.mode.name == "AUTO_LOITER"  # COM_OBL_RC_ACT 0 (Position) falls back to Hold without RC


def test_a_hovering_vehicle_whose_commands_stop_descends_lands_and_disarms() -> None:
    plant = Plant(**LAND)
    plant.hovering()
    plant.run(0.5, True, ARMED, plant.hover)
    fastest_descent = touchdown_speed = 0.0
    for _ in range(40 * S // plant.sim.imu_period_us):
        was_airborne = not plant.truth.on_ground
        vz = plant.truth.velocity[2]
        plant.step(False, ARMED, plant.hover)
        fastest_descent = max(fastest_descent, abs(vz))
        if was_airborne and plant.truth.on_ground:
            touchdown_speed = abs(vz)
        if plant.control is MotorControl.DISARMED:
            break
    assert plant.truth.on_ground and plant.control is MotorControl.DISARMED
    assert 0.5 < fastest_descent < 3.0 and touchdown_speed < 1.5
    assert plant.step(False, ARMED, plant.hover) == (0.0,) * 4
    events = plant.failsafe.take_events()
    assert [level for level, _ in events] == [logging.WARNING, logging.INFO]
    assert "(landed, COM_DISARM_LAND)" in events[1][1]


def test_hold_keeps_the_vehicle_where_the_commands_stopped() -> None:
    plant = Plant(COM_OBL_RC_ACT=int(OffboardLossAction.HOLD))
    plant.hovering()
    plant.run(0.5, True, ARMED, plant.hover)
    plant.run(10.0, False, ARMED, plant.hover)
    assert plant.control is MotorControl.FAILSAFE and plant.failsafe.status()["plant_mode"] == "AUTO.LOITER"
    assert abs(plant.truth.position[2] + 10.0) < 1.0 and max(abs(v) for v in plant.truth.velocity) < 0.3
    assert "holds its position" in plant.failsafe.take_events()[0][1]


def test_commands_returning_mid_descent_hand_control_back_at_once() -> None:
    plant = Plant(**LAND)
    plant.hovering()
    plant.run(0.5, True, ARMED, plant.hover)
    plant.run(3.0, False, ARMED, plant.hover)
    assert plant.control is MotorControl.FAILSAFE and not plant.truth.on_ground
    plant.failsafe.take_events()
    commands = (0.6, 0.6, 0.6, 0.6)
    assert plant.step(True, ARMED, commands) is commands
    assert plant.control is MotorControl.STACK
    [(level, text)] = plant.failsafe.take_events()
    assert level == logging.INFO and "control returns to it" in text
    plant.run(0.5, True, ARMED, plant.hover)
    plant.run(1.1, False, ARMED, plant.hover)  # silent again: the plant takes over again
    assert plant.control is MotorControl.FAILSAFE


def test_the_plant_disarmed_stays_disarmed_until_the_stack_disarms_then_the_stack_drives_again() -> None:
    plant = Plant(**LAND, COM_DISARM_PRFLT=0.5)
    plant.run(0.5, True, ARMED, (0.1,) * 4)  # armed on the ground, idling
    plant.run(3.0, False, ARMED, (0.1,) * 4)  # silent: Land on the ground, disarmed before takeoff
    assert plant.control is MotorControl.DISARMED
    spin = (0.7,) * 4
    assert "(no takeoff, COM_DISARM_PRFLT)" in plant.failsafe.take_events()[-1][1]
    for _ in range(100):
        assert plant.step(True, ARMED, spin) == (0.0,) * 4  # the stack's commands return: still disarmed
    assert plant.control is MotorControl.DISARMED and plant.failsafe.events == []
    zeros = (0.0,) * 4
    assert plant.step(True, DISARMED, zeros) is zeros
    assert plant.control is MotorControl.STACK
    [(level, text)] = plant.failsafe.take_events()
    assert level == logging.INFO and "drive the plant again" in text
    assert plant.step(True, ARMED, spin) is spin  # armed again: the stack's commands drive
    assert plant.control is MotorControl.STACK and plant.failsafe.mode.name == "OFFBOARD"


def test_a_restarted_stack_that_says_disarmed_does_not_stop_the_plant_in_the_air_a_kill_does() -> None:
    """The flight-control host's stack started again after its loss knows nothing of the flight: disarmed."""
    plant = Plant(**LAND)
    plant.hovering()
    plant.run(0.5, True, ARMED, plant.hover)
    plant.run(2.0, False, ARMED, plant.hover)  # lost: the plant lands
    zeros = (0.0,) * 4
    plant.run(2.0, True, DISARMED, zeros)  # the restarted stack's idle outputs, disarmed
    assert plant.control is MotorControl.FAILSAFE and not plant.truth.on_ground
    assert max(abs(v) for v in plant.truth.velocity) < 3.0
    for _ in range(30 * S // plant.sim.imu_period_us):
        if plant.step(True, DISARMED, zeros) is zeros:
            break
    assert plant.truth.on_ground and plant.control is MotorControl.STACK  # landed: the stack's (disarmed) again
    assert max(abs(v) for v in plant.truth.velocity) < 0.1

    killed = Plant(**LAND)
    killed.hovering()
    killed.run(0.5, True, ARMED, killed.hover)
    killed.run(2.0, False, ARMED, killed.hover)
    assert killed.step(True, ActuatorArmed(armed=True, kill=True), zeros) is zeros
    assert killed.control is MotorControl.STACK


def test_the_disarm_action_stops_the_motors_at_once() -> None:
    plant = Plant(COM_OBL_RC_ACT=int(OffboardLossAction.DISARM))
    plant.run(0.5, True, ARMED, (0.1,) * 4)
    plant.run(1.1, False, ARMED, (0.1,) * 4)
    assert plant.control is MotorControl.DISARMED
    warning, info = plant.failsafe.take_events()
    assert "the plant disarms on its own" in warning[1] and "COM_OBL_RC_ACT Disarm" in info[1]
