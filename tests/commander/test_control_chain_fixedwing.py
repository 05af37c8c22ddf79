"""The control-chain watch of a plane: the fixed-wing modules' outputs, and PX4's action for each loss."""

import pytest

from stack.commander import commands as C
from stack.commander.control_chain import FW_CHAIN, SILENCE_US, ControlChainMonitor, Loss
from stack.commander.modes import control_mode
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleStatus as NS
from tests.commander.plane_helpers import flying_plane, plane_clock

FW = NS.VEHICLE_TYPE_FIXED_WING
HOLD = control_mode(NS.NAVIGATION_STATE_AUTO_LOITER, True, FW)


def _monitor() -> ControlChainMonitor:
    monitor = ControlChainMonitor(FW_CHAIN)
    for link in FW_CHAIN:
        monitor.output_seen(link.output, 0)
    assert monitor.update(0, True, HOLD) == []
    return monitor


def _faults(monitor: ControlChainMonitor, now: int, silent: str, mode=HOLD) -> list[tuple[str, Loss]]:
    """The faults at ``now``, every output but ``silent``'s arriving every 10 ms until then."""
    for t in (*range(0, now, 10_000), now):
        for link in FW_CHAIN:
            if link.module != silent:
                monitor.output_seen(link.output, t)
    return [(f.module, f.loss) for f in monitor.update(now, True, mode)]


@pytest.mark.parametrize(
    ("module", "loss"),
    [
        ("fw_att_control", Loss.ATTITUDE_CONTROL),
        ("control_allocator", Loss.ATTITUDE_CONTROL),
        ("attitude_estimator_q", Loss.ATTITUDE_CONTROL),
        ("fw_pos_control", Loss.POSITION_CONTROL),
        ("local_position_estimator", Loss.POSITION_CONTROL),
    ],
)
def test_a_silent_fixed_wing_module_is_named_past_the_silence_limit(module, loss):
    monitor = _monitor()
    assert _faults(monitor, SILENCE_US, module) == []
    assert _faults(monitor, SILENCE_US + 1, module) == [(module, loss)]


@pytest.mark.parametrize(("module", "limit_us"), [("navigator", 225_000), ("airspeed_selector", 450_000)])
def test_the_slower_modules_have_their_periods_stretched_limit(module, limit_us):
    # The navigator at 20 Hz and the airspeed selector at 10 Hz: 2.5 and 5 times the 50 Hz loops' 90 ms.
    monitor = _monitor()
    assert _faults(monitor, limit_us, module) == []
    loss = Loss.POSITION_CONTROL if module == "navigator" else Loss.AIRSPEED
    assert _faults(monitor, limit_us + 1, module) == [(module, loss)]


@pytest.mark.parametrize(
    ("nav_state", "watched"),
    [
        (NS.NAVIGATION_STATE_MANUAL, set()),  # direct: the sticks drive the surfaces through the allocator
        (NS.NAVIGATION_STATE_STAB, {"fw_att_control"}),
        (NS.NAVIGATION_STATE_ALTCTL, {"fw_att_control", "fw_pos_control"}),
        (NS.NAVIGATION_STATE_DESCEND, {"fw_att_control", "fw_pos_control"}),  # the navigator has no part in it
        (NS.NAVIGATION_STATE_AUTO_MISSION, {"fw_att_control", "fw_pos_control", "navigator"}),
    ],
)
def test_which_modules_each_mode_watches(nav_state, watched):
    always = {"attitude_estimator_q", "local_position_estimator", "airspeed_selector", "control_allocator"}
    mode = control_mode(nav_state, True, FW)
    monitor = ControlChainMonitor(FW_CHAIN)
    for link in FW_CHAIN:
        monitor.output_seen(link.output, 0)
    monitor.update(0, True, mode)
    late = 10 * 450_000
    for t in range(0, late + 1, 10_000):  # the attitude estimator alone goes on: every other is silent
        monitor.output_seen(ORB_ID.vehicle_attitude, t)
    assert {f.module for f in monitor.update(late, True, mode)} == (watched | always) - {"attitude_estimator_q"}


@pytest.mark.parametrize("module", ["fw_att_control", "control_allocator"])
def test_losing_attitude_control_in_the_air_terminates(module):
    clock = flying_plane()
    clock.keep_alive(0.1, but=module)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION
    assert clock.status.control_lost_modules == [module]
    assert f"{module} silent: attitude control lost" in clock.events
    assert clock.last.actuator_armed.termination


@pytest.mark.parametrize("module", ["navigator", "fw_pos_control"])
def test_losing_position_control_descends(module):
    clock = flying_plane()
    clock.commander.chain.module_died(module)
    clock.keep_alive(0.02, but=module)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_DESCEND
    assert (clock.last.failsafe_action, clock.last.failsafe_cause) == ("descend", "position_control_loss")
    assert f"{module} dead: position control lost" in clock.events
    # Descending until the user changes mode, even once the module is no longer watched (the navigator in
    # Descend) or is back.
    clock.commander.chain.module_alive(module)
    clock.keep_alive(1.0)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_DESCEND


def test_losing_the_airspeed_only_warns():
    clock = flying_plane()
    clock.keep_alive(0.5, but="airspeed_selector")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert (clock.last.failsafe_action, clock.last.failsafe_cause) == ("warn", "airspeed_loss")
    assert clock.status.control_lost_modules == ["airspeed_selector"]
    assert "airspeed_selector silent: airspeed lost" in clock.events
    assert "Failsafe warning (airspeed_loss)" in clock.events


def test_a_dead_fixed_wing_controller_on_the_ground_disarms():
    clock = plane_clock()
    clock.step()
    clock.send(C.set_mode_command("stabilized"))
    clock.send(C.arm_command())
    clock.keep_alive(0.02)
    clock.commander.chain.module_died("fw_att_control")
    clock.keep_alive(0.02, but="fw_att_control")
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED
    assert "fw_att_control dead: attitude control lost" in clock.events
