"""Simulated battery (PX4's battery simulator: timed drain SIM_BAT_DRAIN, floor SIM_BAT_MIN_PCT, no current
sensor) and GPS switched off and on.

Covers the battery model, the simulator core's GPS switch, and the simulator module's glue (failure injection,
SIM_GPS_USED, battery_status) through a stand-in runtime.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import pytest

from stack.msg.system import ActuatorArmed, BatteryWarning, VehicleCommand
from stack.params.store import ParamStore
from stack.runtime.spec import ModuleSpec, resolve_args
from stack.sim.battery import BatteryModel, BatteryState
from stack.sim.module import SimulatorModule
from stack.sim.sensors import BaroSample, GpsParams, GpsSample, ImuSample, MagSample
from stack.sim.simulator import Simulator

CMD = VehicleCommand
DT = 0.1  # the simulator module's battery period


def drain(battery: BatteryModel, seconds: float, armed: bool = True) -> BatteryState:
    state = battery.update(DT, armed)
    for _ in range(round(seconds / DT) - 1):
        state = battery.update(DT, armed)
    return state


def no_current_sensor(state: BatteryState) -> bool:
    """The current, its average and the charge drawn unknown (-1), and so the time remaining (NaN)."""
    unknown = (state.current_a, state.current_average_a, state.discharged_mah)
    return unknown == (-1.0, -1.0, -1.0) and math.isnan(state.time_remaining_s)


# ---------------------------------------------------------------------------------------------- battery model


def test_a_battery_never_armed_stays_full():
    state = drain(BatteryModel(), 100.0, armed=False)
    assert state.remaining == 1.0 and no_current_sensor(state)
    assert state.warning == BatteryWarning.NONE
    assert state.voltage_v == pytest.approx(4 * 4.05)
    assert state.connected and state.cell_count == 4 and state.capacity == 5000.0


def test_timed_drain_empties_the_pack_linearly_over_sim_bat_drain():
    battery = BatteryModel({"SIM_BAT_DRAIN": 100.0, "SIM_BAT_MIN_PCT": 0.0})
    state = drain(battery, 25.0)
    assert state.remaining == pytest.approx(0.75)
    # As PX4's simulated pack: no current measured, the voltage that of the charge with no load.
    assert no_current_sensor(state)
    assert state.voltage_v == pytest.approx(4 * (3.6 + 0.75 * 0.45))
    assert drain(battery, 50.0).remaining == pytest.approx(0.25)


def test_a_drain_of_0_keeps_the_charge():
    state = drain(BatteryModel({"SIM_BAT_DRAIN": 0.0, "SIM_BAT_MIN_PCT": 0.0}), 600.0)
    assert state.remaining == 1.0 and state.voltage_v == pytest.approx(4 * 4.05)


def test_changing_sim_bat_drain_mid_flight_changes_the_rate_from_then_on():
    battery = BatteryModel({"SIM_BAT_DRAIN": 100.0, "SIM_BAT_MIN_PCT": 0.0})
    assert drain(battery, 10.0).remaining == pytest.approx(0.9)
    battery.set_params({"SIM_BAT_DRAIN": 50.0, "SIM_BAT_MIN_PCT": 0.0})
    assert drain(battery, 10.0).remaining == pytest.approx(0.7)


@pytest.mark.parametrize(
    ("floor_pct", "warning"),
    [
        (20.0, BatteryWarning.NONE),
        (10.0, BatteryWarning.LOW),  # below BAT_LOW_THR 0.15
        (6.0, BatteryWarning.CRITICAL),  # below BAT_CRIT_THR 0.07
        (4.0, BatteryWarning.EMERGENCY),  # below BAT_EMERGEN_THR 0.05
    ],
)
def test_the_drain_stops_at_sim_bat_min_pct_with_the_warning_of_that_charge(floor_pct, warning):
    battery = BatteryModel({"SIM_BAT_DRAIN": 30.0, "SIM_BAT_MIN_PCT": floor_pct})
    state = drain(battery, 60.0)
    assert state.remaining == pytest.approx(floor_pct / 100.0)
    assert state.warning == warning
    assert drain(battery, 60.0).remaining == pytest.approx(floor_pct / 100.0)


def test_the_default_floor_never_reaches_a_warning():
    state = drain(BatteryModel(), 600.0)
    assert state.remaining == pytest.approx(0.5) and state.warning == BatteryWarning.NONE


def test_sim_bat_min_pct_100_never_drains():
    assert drain(BatteryModel({"SIM_BAT_MIN_PCT": 100.0}), 120.0).remaining == 1.0


def test_the_warning_stays_latched_while_armed_and_clears_on_disarming():
    battery = BatteryModel({"SIM_BAT_DRAIN": 10.0, "SIM_BAT_MIN_PCT": 0.0})
    assert drain(battery, 9.4).warning == BatteryWarning.CRITICAL
    battery.set_params({"SIM_BAT_DRAIN": 10.0, "SIM_BAT_MIN_PCT": 50.0})  # the charge jumps up to the floor
    state = battery.update(DT, armed=True)
    assert state.remaining == pytest.approx(0.5)
    assert state.warning == BatteryWarning.CRITICAL
    state = battery.update(DT, armed=False)
    assert (state.remaining, state.warning) == (1.0, BatteryWarning.NONE)


def test_voltage_falls_with_the_charge_and_scales_with_the_cell_count():
    battery = BatteryModel({"SIM_BAT_DRAIN": 20.0, "SIM_BAT_MIN_PCT": 0.0, "BAT1_N_CELLS": 6})
    voltages = [battery.update(DT, True).voltage_v for _ in range(150)]
    assert all(b < a for a, b in itertools.pairwise(voltages))
    assert battery.open_circuit_voltage(1.0) == pytest.approx(6 * 4.05)
    assert battery.open_circuit_voltage(0.0) == pytest.approx(6 * 3.6)
    empty = drain(battery, 10.0)
    assert empty.remaining == 0.0 and empty.voltage_v == pytest.approx(6 * 3.6)


def test_a_zero_time_step_changes_nothing():
    battery = BatteryModel({"SIM_BAT_DRAIN": 10.0, "SIM_BAT_MIN_PCT": 0.0})
    before = drain(battery, 5.0)
    after = battery.update(0.0, armed=True)
    assert after == before


# ---------------------------------------------------------------------------------------------- GPS on and off


def gps_samples(sim: Simulator, seconds: float) -> list[GpsSample]:
    samples = []
    for _ in range(round(seconds * 250)):
        samples.extend(s for s in sim.advance((0.0,) * 4) if isinstance(s, GpsSample))
    return samples


def test_gps_configured_off_starts_without_a_fix_until_switched_on():
    sim = Simulator(seed=7, gps=GpsParams(enabled=False))
    assert not sim.gps_enabled
    off = gps_samples(sim, 1.0)
    assert len(off) == 10
    for s in off:
        assert (s.fix_type, s.satellites, s.eph, s.epv, s.hdop, s.vdop) == (0, 0, 100.0, 100.0, 99.99, 99.99)
        assert all(math.isnan(v) for v in (s.lat, s.lon, s.alt_msl, *s.vel_ned, s.s_variance_m_s))
    sim.set_gps_enabled(True)
    on = gps_samples(sim, 1.0)
    assert len(on) == 10 and all(s.fix_type == 3 and math.isfinite(s.lat) for s in on)


def test_measurements_taken_before_the_gps_went_off_are_still_published_after_the_delay():
    sim = Simulator(seed=8, gps=GpsParams(delay=0.25))
    gps_samples(sim, 1.0)
    sim.set_gps_enabled(False)
    off_at = sim.time_us
    published = gps_samples(sim, 1.0)
    sim.set_gps_enabled(True)
    on_at = sim.time_us
    published += gps_samples(sim, 1.0)
    assert [s.time_us < off_at or s.time_us >= on_at for s in published] == [s.fix_type == 3 for s in published]
    # Measured at 0.804 s and 0.904 s, still in flight (published 0.25 s later) when the GPS went off at 1 s.
    assert [s.time_us for s in published if s.time_us < off_at] == [804_000, 904_000]
    assert sum(s.fix_type == 0 for s in published) == 10


def test_a_gps_outage_leaves_the_other_sensors_untouched():
    def other_sensors(toggle: bool) -> list[Any]:
        sim = Simulator(seed=9)
        samples = []
        for step in range(500):
            if toggle:
                sim.set_gps_enabled(not 100 <= step < 300)
            samples.extend(s for s in sim.advance((0.3,) * 4) if isinstance(s, ImuSample | MagSample | BaroSample))
        return samples

    assert other_sensors(True) == other_sensors(False)


# ---------------------------------------------------------------------------------------------- simulator module


class _Input:
    def __init__(self) -> None:
        self.latest: Any = None
        self.queue: list[Any] = []

    def take(self) -> list[Any]:
        messages, self.queue = self.queue, []
        return messages

    def update(self) -> Any:
        return None  # the tests set ``latest``: no new message counts as arrived


class _Output:
    def __init__(self) -> None:
        self.messages: list[Any] = []

    def publish(self, msg: Any, now_us: int) -> None:
        self.messages.append(msg)


class StandInRuntime:
    """What a module reads from its runtime (parameters, arguments, inputs, outputs, clock), in memory."""

    def __init__(self, params: dict[str, object] | None = None) -> None:
        self.name = SimulatorModule.NAME
        self.spec = ModuleSpec(name=self.name, module="stack.sim.module:SimulatorModule", seed=3)
        self.params = ParamStore(SimulatorModule.PARAMS, params)
        self.args = resolve_args(SimulatorModule.ARGS, {})
        self.inputs: dict[tuple[str, int], _Input] = {}
        self.outputs: dict[tuple[str, int], _Output] = {}
        self.now = 0
        self.rejected = 0

    def add_input(self, topic: str, instance: int, queue: bool, capacity: int) -> None:
        self.inputs[(topic, instance)] = _Input()

    def add_output(self, topic: str, instance: int, reliable: bool | None) -> None:
        self.outputs[(topic, instance)] = _Output()

    def now_us(self) -> int:
        return self.now

    def published(self, topic: str) -> list[Any]:
        return self.outputs[(topic, 0)].messages


def simulator_module(**params: object) -> tuple[SimulatorModule, StandInRuntime]:
    rt = StandInRuntime(params)
    return SimulatorModule(rt), rt


def run(module: SimulatorModule, rt: StandInRuntime, seconds: float) -> None:
    for _ in range(round(seconds * 1e6 / module.step_period_us())):
        rt.now += module.step_period_us()
        module.run(None, module.step_period_us() * 1e-6)


def command(rt: StandInRuntime, cmd: VehicleCommand) -> None:
    rt.inputs[("vehicle_command", 0)].queue.append(cmd)


def inject_gps(kind: int, unit: int = CMD.FAILURE_UNIT_SENSOR_GPS) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_INJECT_FAILURE, param1=float(unit), param2=float(kind))


def test_inject_failure_switches_the_simulated_gps_off_and_back_on():
    module, rt = simulator_module(SYS_FAILURE_EN=1)
    command(rt, inject_gps(CMD.FAILURE_TYPE_OFF))
    run(module, rt, 0.5)
    assert not module.sim.gps_enabled
    assert all(m.fix_type == 0 and m.satellites_used == 0 for m in rt.published("sensor_gps"))
    command(rt, inject_gps(CMD.FAILURE_TYPE_OK))
    run(module, rt, 0.004)
    assert module.sim.gps_enabled


@pytest.mark.parametrize(
    "cmd",
    [
        inject_gps(2),  # a failure type that is not simulated
        inject_gps(CMD.FAILURE_TYPE_OFF, unit=CMD.FAILURE_UNIT_SENSOR_GYRO),  # a unit that is not simulated
        CMD(command=CMD.VEHICLE_CMD_NAV_LAND, param1=4.0, param2=1.0),  # not a failure injection
    ],
)
def test_other_commands_and_unsimulated_failures_leave_the_gps_on(cmd):
    module, rt = simulator_module(SYS_FAILURE_EN=1)
    command(rt, cmd)
    run(module, rt, 0.2)
    assert module.sim.gps_enabled
    assert all(m.fix_type == 3 for m in rt.published("sensor_gps"))


def test_failure_injection_is_ignored_while_sys_failure_en_is_0():
    module, rt = simulator_module()  # the commander denies it too
    command(rt, inject_gps(CMD.FAILURE_TYPE_OFF))
    run(module, rt, 0.2)
    assert module.sim.gps_enabled
    rt.params.set("SYS_FAILURE_EN", 1)
    module.on_params_changed(rt.params.take_changes())
    command(rt, inject_gps(CMD.FAILURE_TYPE_OFF))
    run(module, rt, 0.004)
    assert not module.sim.gps_enabled


def test_sim_gps_used_below_4_satellites_is_a_gps_loss():
    module, _ = simulator_module(SIM_GPS_USED=3)
    assert not module.sim.gps_enabled
    module, rt = simulator_module()
    rt.params.set("SIM_GPS_USED", 3)
    module.on_params_changed(rt.params.take_changes())
    assert not module.sim.gps_enabled
    rt.params.set("SIM_GPS_USED", 4)
    module.on_params_changed(rt.params.take_changes())
    assert module.sim.gps_enabled


def test_battery_status_drains_at_10_hz_while_armed_and_refills_when_disarmed():
    module, rt = simulator_module(SIM_BAT_DRAIN=10.0, SIM_BAT_MIN_PCT=0.0)
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=False)  # the stack, disarmed first
    module.motor_commands()
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=True)
    run(module, rt, 1.0)
    status = rt.published("battery_status")
    assert len(status) == 10
    assert [round(s.remaining, 6) for s in status] == [round(1.0 - 0.01 * k, 6) for k in range(1, 11)]
    rt.params.set("SIM_BAT_MIN_PCT", 95.0)
    module.on_params_changed(rt.params.take_changes())
    run(module, rt, 1.0)
    assert status[-1].remaining == pytest.approx(0.95)
    rt.inputs[("actuator_armed", 0)].latest = ActuatorArmed(armed=False)
    run(module, rt, 0.1)
    assert status[-1].remaining == 1.0 and status[-1].current_a == -1.0
