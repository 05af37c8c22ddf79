"""Small real modules that exercise the runtime in tests: a lockstep clock source and a processing chain.

Their arithmetic is chosen so that every output depends on which inputs a run saw: if a module saw
a message one step early or late, the recorded trace changes, so the determinism tests can fail.
"""

from __future__ import annotations

import json
import logging
import os
import random
import time
from pathlib import Path

from stack.msg.estimation import VehicleAngularVelocity
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorGyro
from stack.msg.setpoints import VehicleRatesSetpoint, VehicleTorqueSetpoint
from stack.msg.system import VehicleCommand, VehicleCommandAck
from stack.params.param import Param
from stack.runtime.module import Arg, Module, Timer, Trigger
from stack.runtime.priority import PLANT

log = logging.getLogger("tests.support.modules")


class TickSource(Module):
    """Drives lockstep (or a wall-clock timer) and publishes a seeded pseudo-random 'gyro' each step."""

    NAME = "tick_source"
    PUBLISHES = (ORB_ID.sensor_gyro,)
    LOCKSTEP_COORDINATOR = True
    # It stands for the simulator, and on the wall clock keeps its rate as the simulator does beside a busy machine.
    WORK_QUEUE = PLANT
    ARGS = (Arg("rate_hz", 250.0), Arg("trace", ""), Arg("crash_at_step", 0), Arg("steps", 0))
    PARAMS = (Param("TEST_GAIN", 1.0, -10.0, 10.0, doc="Scale of the generated signal"),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.advertise(ORB_ID.sensor_gyro)
        self.subscribe(ORB_ID.vehicle_torque_setpoint)
        self.rng = random.Random(rt.spec.seed)
        self.step = 0
        self.trace: list[list[float]] = []

    def step_period_us(self) -> int:
        return round(1e6 / float(self.args["rate_hz"]))

    def run(self, msg: object, dt: float) -> None:
        self.step += 1
        if self.step == self.args["crash_at_step"]:
            os._exit(3)
        torque = self.latest(ORB_ID.vehicle_torque_setpoint)
        if torque is not None:
            self.trace.append([self.now_us(), *torque.xyz])
        gain = float(self.params["TEST_GAIN"])
        t = self.now_us()
        x = gain * self.rng.uniform(-1.0, 1.0)
        self.publish(
            ORB_ID.sensor_gyro, SensorGyro(timestamp_sample=t, x=x, y=2.0 * x, z=torque.xyz[0] if torque else 0.0)
        )
        if self.args["steps"] and self.step >= self.args["steps"]:
            self.close()
            raise SystemExit(0)

    def close(self) -> None:
        if self.args["trace"] and self.trace:
            Path(str(self.args["trace"])).write_text(json.dumps(self.trace))
            self.trace = []


class Doubler(Module):
    """Triggered by sensor_gyro: publishes twice the gyro plus the latest rates setpoint it can see."""

    NAME = "doubler"
    PUBLISHES = (ORB_ID.vehicle_angular_velocity,)
    TRIGGER = Trigger(ORB_ID.sensor_gyro)
    PARAMS = (Param("TEST_OFFSET", 0.0, -100.0, 100.0),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_rates_setpoint)
        self.advertise(ORB_ID.vehicle_angular_velocity)
        self.offset = float(self.params["TEST_OFFSET"])

    def on_params_changed(self, changed: set[str]) -> None:
        self.offset = float(self.params["TEST_OFFSET"])

    def run(self, msg: SensorGyro, dt: float) -> None:
        sp = self.latest(ORB_ID.vehicle_rates_setpoint)
        extra = sp.roll if sp is not None else 0.0
        self.publish(
            ORB_ID.vehicle_angular_velocity,
            VehicleAngularVelocity(
                timestamp_sample=msg.timestamp_sample,
                xyz=(2.0 * msg.x + extra + self.offset, msg.y, msg.z),
                xyz_derivative=(dt, 0.0, 0.0),
            ),
        )


class Summer(Module):
    """Triggered by vehicle_angular_velocity: torque = rate + the pacer's latest setpoint."""

    NAME = "summer"
    PUBLISHES = (ORB_ID.vehicle_torque_setpoint,)
    TRIGGER = Trigger(ORB_ID.vehicle_angular_velocity)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_rates_setpoint)
        self.advertise(ORB_ID.vehicle_torque_setpoint)
        self.acc = 0.0

    def run(self, msg: VehicleAngularVelocity, dt: float) -> None:
        sp = self.latest(ORB_ID.vehicle_rates_setpoint)
        self.acc = 0.9 * self.acc + msg.xyz[0] + (sp.pitch if sp is not None else 0.0)
        self.publish(
            ORB_ID.vehicle_torque_setpoint,
            VehicleTorqueSetpoint(timestamp_sample=msg.timestamp_sample, xyz=(self.acc, msg.xyz[0], dt)),
        )


class Pacer(Module):
    """A timer module: every period, a setpoint derived from the latest angular velocity it sees."""

    NAME = "pacer"
    PUBLISHES = (ORB_ID.vehicle_rates_setpoint,)
    TRIGGER = Timer(50.0)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_angular_velocity)
        self.advertise(ORB_ID.vehicle_rates_setpoint)
        self.n = 0

    def run(self, msg: None, dt: float) -> None:
        av = self.latest(ORB_ID.vehicle_angular_velocity)
        self.n += 1
        value = av.xyz[0] if av is not None else 0.0
        self.publish(ORB_ID.vehicle_rates_setpoint, VehicleRatesSetpoint(roll=0.5 * value, pitch=float(self.n), yaw=dt))


class CommandCounter(Module):
    """A timer module that answers every vehicle_command (queue input) with an ack counting them."""

    NAME = "command_counter"
    PUBLISHES = (ORB_ID.vehicle_command_ack,)
    TRIGGER = Timer(20.0)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_command, queue=True)
        self.advertise(ORB_ID.vehicle_command_ack)
        self.count = 0

    def run(self, msg: None, dt: float) -> None:
        for cmd in self.take(ORB_ID.vehicle_command):
            self.count += 1
            self.publish(ORB_ID.vehicle_command_ack, VehicleCommandAck(command=cmd.command, result_param2=self.count))


class Watcher(Module):
    """Follows the module processes of its vehicle, as the commander does, logging each start and end."""

    NAME = "watcher"
    TRIGGER = Timer(20.0)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.watch_modules(self._on_module)

    def _on_module(self, module: str, pid: int, alive: bool) -> None:
        log.info("module %s %s (pid %d)", module, "alive" if alive else "gone", pid)

    def run(self, msg: None, dt: float) -> None:
        pass


class Crasher(Module):
    """Exits with an error after a number of wall-clock ticks (restart-policy tests)."""

    NAME = "crasher"
    PUBLISHES = (ORB_ID.vehicle_command,)
    TRIGGER = Timer(20.0)
    ARGS = (Arg("ticks", 10), Arg("marker", ""))

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.advertise(ORB_ID.vehicle_command)
        self.ticks = 0
        if self.args["marker"]:
            with open(str(self.args["marker"]), "a") as f:
                f.write(f"{os.getpid()}\n")

    def run(self, msg: None, dt: float) -> None:
        self.ticks += 1
        if self.ticks >= int(self.args["ticks"]):
            raise SystemExit(4)
        self.publish(ORB_ID.vehicle_command, VehicleCommand(command=VehicleCommand.VEHICLE_CMD_NAV_LOITER_UNLIM))


class Staller(Module):
    """Triggered by sensor_gyro; hangs forever on its N-th run (lockstep stall detection tests)."""

    NAME = "staller"
    TRIGGER = Trigger(ORB_ID.sensor_gyro)
    ARGS = (Arg("stall_at", 100),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.runs = 0

    def run(self, msg: SensorGyro, dt: float) -> None:
        self.runs += 1
        if self.runs == self.args["stall_at"]:
            while True:
                time.sleep(1.0)


class Untriggered(Module):
    """Triggered by a topic nothing in the chain publishes: a lockstep member that never runs."""

    NAME = "untriggered"
    TRIGGER = Trigger(ORB_ID.vehicle_thrust_setpoint)

    def run(self, msg: object, dt: float) -> None:
        raise AssertionError("nothing publishes vehicle_thrust_setpoint in the test chain")


class Probe(Module):
    """Triggered by sensor_gyro: records which input messages each run could see, into a JSON file."""

    NAME = "probe"
    TRIGGER = Trigger(ORB_ID.sensor_gyro)
    ARGS = (Arg("out", ""),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.vehicle_rates_setpoint)
        self.subscribe(ORB_ID.vehicle_angular_velocity)
        self.seen: list[list[float]] = []

    def run(self, msg: SensorGyro, dt: float) -> None:
        sp = self.latest(ORB_ID.vehicle_rates_setpoint)
        av = self.latest(ORB_ID.vehicle_angular_velocity)
        self.seen.append(
            [self.now_us(), msg.timestamp_sample, sp.timestamp if sp else -1, av.timestamp if av else -1, dt]
        )

    def close(self) -> None:
        if self.args["out"]:
            Path(str(self.args["out"])).write_text(json.dumps(self.seen))


class SlowStart(Module):
    """Takes ``seconds`` to start (a start-up a signal can interrupt)."""

    NAME = "slow_start"
    TRIGGER = Timer(10.0)
    ARGS = (Arg("seconds", 60.0),)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        time.sleep(float(self.args["seconds"]))

    def run(self, msg: object, dt: float) -> None:
        pass


class BrokenInit(Module):
    """Fails while starting (supervisor failure handling)."""

    NAME = "broken_init"
    TRIGGER = Timer(10.0)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        raise RuntimeError("cannot start: the hardware is missing")
