"""Test modules for what a triggered run sees of the messages published at its own time."""

from __future__ import annotations

from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorGyro
from stack.runtime.module import Module, Trigger


class AccelThenGyro(Module):
    """A 250 Hz lockstep clock publishing an accelerometer sample, then a gyro sample, each step."""

    NAME = "accel_then_gyro"
    PUBLISHES = (ORB_ID.sensor_accel, ORB_ID.sensor_gyro)
    LOCKSTEP_COORDINATOR = True

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.advertise(ORB_ID.sensor_accel)
        self.advertise(ORB_ID.sensor_gyro)

    def step_period_us(self) -> int:
        return 4000

    def run(self, msg: None, dt: float) -> None:
        t = self.now_us()
        self.publish(ORB_ID.sensor_accel, SensorAccel(timestamp_sample=t))
        self.publish(ORB_ID.sensor_gyro, SensorGyro(timestamp_sample=t))


class SameTimeProbe(Module):
    """Triggered by sensor_gyro: notes the time of the latest accelerometer sample and angular velocity it sees."""

    NAME = "same_time_probe"
    TRIGGER = Trigger(ORB_ID.sensor_gyro)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.sensor_accel)
        self.subscribe(ORB_ID.vehicle_angular_velocity)
        self.seen: list[tuple[int, int, int]] = []

    def run(self, msg: SensorGyro, dt: float) -> None:
        accel, rates = self.latest(ORB_ID.sensor_accel), self.latest(ORB_ID.vehicle_angular_velocity)
        self.seen.append((self.now_us(), accel.timestamp if accel else -1, rates.timestamp if rates else -1))
