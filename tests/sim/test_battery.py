import math

import pytest

from stack.msg.system import BatteryWarning
from stack.sim.battery import BatteryModel, motor_current


def _run(battery, seconds, armed=True, current=math.nan, dt=0.1):
    state = None
    for _ in range(round(seconds / dt)):
        state = battery.update(dt, armed, current)
    return state


def test_timed_drain_is_linear_and_stops_at_the_floor():
    battery = BatteryModel({"SIM_BAT_DRAIN": 60.0, "SIM_BAT_MIN_PCT": 20.0})
    state = _run(battery, 30.0)
    assert state.remaining == pytest.approx(0.5)
    assert state.discharged_mah == pytest.approx(2500.0)
    # The current that empties 5000 mAh in 60 s, and the voltage under that load.
    assert state.current_a == pytest.approx(300.0)
    assert state.voltage_v == pytest.approx(4 * (3.6 + 0.5 * 0.45) - 300.0 * 0.005 * 4)
    assert _run(battery, 60.0).remaining == pytest.approx(0.2)


def test_disarming_refills_the_timed_battery():
    battery = BatteryModel({"SIM_BAT_MIN_PCT": 0.0})
    _run(battery, 30.0)
    state = battery.update(0.1, armed=False)
    assert state.remaining == 1.0 and state.discharged_mah == 0.0 and state.current_a == 0.0
    assert state.voltage_v == pytest.approx(4 * 4.05)


def test_default_floor_never_reaches_a_warning():
    state = _run(BatteryModel(), 600.0)
    assert state.remaining == pytest.approx(0.5)
    assert state.warning == BatteryWarning.NONE


def test_electrical_drain_counts_coulombs():
    battery = BatteryModel({"SIM_BAT_DRAIN": 0.0, "BAT1_CAPACITY": 5000.0, "SIM_BAT_MIN_PCT": 0.0})
    state = _run(battery, 360.0, current=10.0)
    assert state.discharged_mah == pytest.approx(1000.0)
    assert state.remaining == pytest.approx(0.8)
    assert state.current_a == 10.0
    assert state.current_average_a == pytest.approx(10.0, rel=1e-3)
    assert state.time_remaining_s == pytest.approx(0.8 * 5000 * 3.6 / 10.0, rel=1e-3)
    # Disarming does not refill a real pack.
    assert battery.update(0.1, False, 0.5).remaining == pytest.approx(0.8, abs=1e-4)


def test_warning_levels_rise_and_only_rise_while_armed():
    battery = BatteryModel({"SIM_BAT_DRAIN": 100.0, "SIM_BAT_MIN_PCT": 0.0})
    levels = []
    for _ in range(1000):
        state = battery.update(0.1, True)
        if not levels or state.warning != levels[-1][1]:
            levels.append((round(state.remaining, 3), state.warning))
    assert [w for _, w in levels] == [
        BatteryWarning.NONE,
        BatteryWarning.LOW,
        BatteryWarning.CRITICAL,
        BatteryWarning.EMERGENCY,
    ]
    assert levels[1][0] == pytest.approx(0.15, abs=0.002)
    assert levels[2][0] == pytest.approx(0.07, abs=0.002)
    assert levels[3][0] == pytest.approx(0.05, abs=0.002)
    assert battery.warning_for(0.5) == BatteryWarning.NONE


def test_motor_current_from_momentum_theory():
    # 1.5 kg quad hovering on four 0.12 m rotors: ~10 A from a 4S pack.
    hover = motor_current([1.5 * 9.81 / 4] * 4, 14.8, 0.12)
    assert 8.0 < hover < 14.0
    # Ideal power grows with thrust^1.5.
    double = motor_current([1.5 * 9.81 / 2] * 4, 14.8, 0.12)
    assert double - 0.5 == pytest.approx((hover - 0.5) * 2**1.5)
    assert motor_current([0.0] * 4, 14.8, 0.12) == 0.5
