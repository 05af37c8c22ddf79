"""Builders for the commander tests: healthy inputs and a commander stepped through time."""

from __future__ import annotations

import dataclasses

from stack.commander.health import CommanderInputs
from stack.commander.state_machine import Commander, CommanderOutputs
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.sensors import SensorGps

REF = (47.397742, 8.545594, 489.4)


def local_position(t_us: int, x: float = 0.0, y: float = 0.0, z: float = 0.0, **fields) -> VehicleLocalPosition:
    values = dict(
        timestamp=t_us,
        xy_valid=True,
        z_valid=True,
        v_xy_valid=True,
        v_z_valid=True,
        x=x,
        y=y,
        z=z,
        eph=0.5,
        epv=0.5,
        ref_lat=REF[0],
        ref_lon=REF[1],
        ref_alt=REF[2],
    )
    values.update(fields)
    return VehicleLocalPosition(**values)


def healthy(t_us: int, position: tuple[float, float, float] = (0.0, 0.0, 0.0), landed: bool = True, **fields):
    """Inputs of a healthy vehicle at ``position`` (local NED) with every sensor and estimate fresh."""
    inputs = CommanderInputs(
        attitude_timestamp_us=t_us,
        angular_velocity_timestamp_us=t_us,
        local_position=local_position(t_us, *position),
        gyro_timestamp_us=t_us,
        accel_timestamp_us=t_us,
        baro_timestamp_us=t_us,
        mag_timestamp_us=t_us,
        gps_timestamp_us=t_us,
        gps_fix_type=SensorGps.FIX_TYPE_3D,
        landed=landed,
        maybe_landed=landed,
    )
    return dataclasses.replace(inputs, **fields)


class Clock:
    """A commander stepped at a fixed rate with inputs made by a function of time."""

    def __init__(
        self,
        commander: Commander,
        t_us: int = 1_000_000,
        period_us: int = 10_000,
        overrides: dict[str, object] | None = None,
    ) -> None:
        self.commander = commander
        self.t = t_us
        self.period = period_us
        self.position = (0.0, 0.0, 0.0)
        self.landed = True
        self.sticks = False
        """Manual control input arrives every cycle."""
        self.overrides: dict[str, object] = dict(overrides or {})
        self.events: list[str] = []
        self.last: CommanderOutputs = commander.update(self.t, self.inputs())

    def inputs(self):
        sticks = {"last_manual_control_us": self.t, "manual_control_valid": True} if self.sticks else {}
        return healthy(self.t, self.position, self.landed, **{**sticks, **self.overrides})

    def step(self, seconds: float = 0.0) -> CommanderOutputs:
        """Advance by ``seconds`` (at least one cycle) and return the last outputs."""
        end = self.t + max(round(seconds * 1e6), self.period)
        while self.t < end:
            self.t += self.period
            self.last = self.commander.update(self.t, self.inputs())
            self.events.extend(self.last.events)
        return self.last

    def send(self, cmd):
        return self.commander.handle_command(cmd, self.t)

    def fly_to(self, position: tuple[float, float, float]) -> CommanderOutputs:
        self.position = position
        self.landed = False
        return self.step()

    @property
    def status(self):
        return self.last.vehicle_status


def make_clock(**params) -> Clock:
    """A commander with ``params`` (failsafe delay off unless given) on a 100 Hz clock."""
    return Clock(Commander({"COM_FAIL_ACT_T": 0.0, **params}))
