"""A dead or silent control module is a failsafe; a restarted commander resumes the flight."""

import pytest

from stack.commander import commands as C
from stack.commander.control_chain import (
    CHAIN,
    OUTPUTS,
    PAUSE_US,
    REALTIME_SILENCE_US,
    SILENCE_US,
    STALE_US,
    ControlChainMonitor,
    Loss,
)
from stack.commander.land_detector import MulticopterLandDetector
from stack.commander.modes import control_mode
from stack.commander.state_machine import Commander
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import Clock, healthy, make_clock

HOLD = control_mode(NS.NAVIGATION_STATE_AUTO_LOITER, True)


def _all_seen(monitor: ControlChainMonitor, t: int) -> None:
    for topic in OUTPUTS:
        monitor.output_seen(topic, t)


def _going_on(monitor: ControlChainMonitor, topics: tuple, start: int, end: int) -> None:
    """``topics`` arriving every 10 ms from ``start`` to ``end``: the chain never pauses."""
    for t in range(start, end + 1, 10_000):
        for topic in topics:
            monitor.output_seen(topic, t)


def test_a_module_is_silent_once_its_output_is_older_than_the_silence_limit():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    assert monitor.update(0, True, HOLD) == []
    assert monitor.update(SILENCE_US, True, HOLD) == []
    for topic in OUTPUTS:
        if topic != ORB_ID.vehicle_torque_setpoint:
            monitor.output_seen(topic, SILENCE_US + 1)
    faults = monitor.update(SILENCE_US + 1, True, HOLD)
    assert [(f.module, f.loss, f.dead) for f in faults] == [("mc_rate_control", Loss.ATTITUDE_CONTROL, False)]
    assert faults[0].describe() == "mc_rate_control silent: attitude control lost"


def test_a_dead_module_is_a_fault_at_once_and_not_after_it_is_back():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    monitor.module_died("mc_pos_control")
    assert [(f.module, f.loss, f.dead) for f in monitor.update(10, True, HOLD)] == [
        ("mc_pos_control", Loss.POSITION_CONTROL, True)
    ]
    monitor.module_alive("mc_pos_control")
    assert monitor.update(20, True, HOLD) == []


def test_nothing_is_watched_disarmed_never_seen_or_outside_its_loop():
    monitor = ControlChainMonitor()
    assert monitor.update(10 * SILENCE_US, True, HOLD) == []  # an external autopilot's profile: none seen
    _all_seen(monitor, 0)
    assert monitor.update(10 * SILENCE_US, False, HOLD) == []
    acro = control_mode(NS.NAVIGATION_STATE_ACRO, True)  # no attitude or position loop in Acro
    later = 20 * SILENCE_US
    for topic in (
        ORB_ID.vehicle_attitude,
        ORB_ID.vehicle_local_position,
        ORB_ID.vehicle_torque_setpoint,
        ORB_ID.actuator_motors,
    ):
        monitor.output_seen(topic, later)
    assert monitor.update(later, True, acro) == []


def test_a_pause_of_the_whole_chain_silences_no_module():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    monitor.update(0, True, HOLD)
    assert monitor.update(10 * SILENCE_US, True, HOLD) == [] and monitor.late


def test_after_a_pause_of_the_whole_chain_each_module_gets_the_silence_limit_to_speak_again():
    """In real time a stalled bus delivers nothing for a while, then the chain's outputs come back in its order: the
    rate loop's (on the estimator's first angular velocity) before the attitude loop's, which waits for the CPU."""
    monitor = ControlChainMonitor(silence_us=REALTIME_SILENCE_US)
    _all_seen(monitor, 0)
    assert monitor.update(0, True, HOLD) == []
    back = REALTIME_SILENCE_US + 100_000
    first = (ORB_ID.vehicle_attitude, ORB_ID.vehicle_local_position, ORB_ID.vehicle_torque_setpoint)
    for topic in (*first, ORB_ID.actuator_motors):
        monitor.output_seen(topic, back)
    assert monitor.update(back, True, HOLD) == []
    others = (*first, ORB_ID.actuator_motors, ORB_ID.trajectory_setpoint, ORB_ID.vehicle_attitude_setpoint)
    end = back + REALTIME_SILENCE_US + 10_000
    _going_on(monitor, others, back, end)  # then mc_att_control stays silent
    faults = monitor.update(end, True, HOLD)
    assert [f.describe() for f in faults] == ["mc_att_control silent: attitude control lost"]


def test_a_gap_shorter_than_a_pause_keeps_counting_a_silent_module():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    monitor.update(0, True, HOLD)
    t = PAUSE_US  # every output a pause long but mc_rate_control's came back; its stays away
    for topic in OUTPUTS:
        if topic != ORB_ID.vehicle_torque_setpoint:
            monitor.output_seen(topic, t)
    assert [f.module for f in monitor.update(t, True, HOLD)] == ["mc_rate_control"]


def test_a_loop_switched_on_gets_the_silence_limit_to_speak():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    acro = control_mode(NS.NAVIGATION_STATE_ACRO, True)
    t = 10 * SILENCE_US
    for topic in OUTPUTS:
        monitor.output_seen(topic, t)
    monitor.update(t, True, acro)
    live = (
        ORB_ID.vehicle_attitude,
        ORB_ID.vehicle_local_position,
        ORB_ID.vehicle_torque_setpoint,
        ORB_ID.actuator_motors,
    )
    for topic in live:
        monitor.output_seen(topic, t + SILENCE_US)
    assert monitor.update(t + SILENCE_US, True, HOLD) == []  # Hold turns position and attitude control on
    for topic in live:
        monitor.output_seen(topic, t + 2 * SILENCE_US + 1)
    assert {f.module for f in monitor.update(t + 2 * SILENCE_US + 1, True, HOLD)} == {
        "flight_mode_manager",
        "mc_pos_control",
        "mc_att_control",
    }


def test_offboard_watches_only_the_estimators_rate_control_and_allocation():
    monitor = ControlChainMonitor()
    offboard = control_mode(NS.NAVIGATION_STATE_OFFBOARD, True)
    offboard.flag_control_rates_enabled = offboard.flag_control_allocation_enabled = True  # as Offboard's glue sets
    offboard.flag_control_attitude_enabled = offboard.flag_multicopter_position_control_enabled = True
    _all_seen(monitor, 0)
    monitor.update(0, True, offboard)
    _going_on(monitor, (ORB_ID.vehicle_attitude,), 0, 10 * SILENCE_US)
    modules = {f.module for f in monitor.update(10 * SILENCE_US, True, offboard)}
    assert modules == {"local_position_estimator", "mc_rate_control", "control_allocator"}


def _hovering() -> Clock:
    clock = make_clock()
    clock.step()
    clock.send(C.arm_command())
    clock.send(C.set_mode_command("hold"))
    clock.fly_to((0.0, 0.0, -5.0))
    for _ in range(3):
        _all_seen(clock.commander.chain, clock.t)
        clock.step()
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    return clock


def _keep_alive(clock: Clock, seconds: float, but: str) -> None:
    """Step while every chain output but ``but``'s keeps coming."""
    silent = next((link.output for link in CHAIN if link.module == but), "")
    end = clock.t + round(seconds * 1e6)
    while clock.t < end:
        for topic in OUTPUTS:
            if topic != silent:
                clock.commander.chain.output_seen(topic, clock.t)
        clock.step()


@pytest.mark.parametrize("module", ["attitude_estimator_q", "mc_att_control", "mc_rate_control", "control_allocator"])
def test_losing_attitude_control_in_the_air_terminates_within_100_ms(module):
    clock = _hovering()
    _keep_alive(clock, 0.1, but=module)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION
    assert clock.status.control_lost_modules == [module]
    assert f"{module} silent: attitude control lost" in clock.events
    assert "Failsafe activated (attitude_control_loss): terminate" in clock.events
    assert clock.last.actuator_armed.termination


@pytest.mark.parametrize("module", ["local_position_estimator", "flight_mode_manager", "mc_pos_control"])
def test_losing_position_control_lands_and_keeps_landing_when_it_is_back(module):
    clock = _hovering()
    _keep_alive(clock, 0.1, but=module)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert (clock.last.failsafe_action, clock.last.failsafe_cause) == ("land", "position_control_loss")
    _keep_alive(clock, 0.5, but="")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    assert clock.status.control_lost_modules == []


def test_a_dead_controller_on_the_ground_disarms():
    clock = make_clock()
    clock.step()
    clock.send(C.arm_command())
    _all_seen(clock.commander.chain, clock.t)
    clock.commander.chain.module_died("mc_rate_control")
    clock.step()
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED
    assert "mc_rate_control dead: attitude control lost" in clock.events


def test_a_restarted_commander_resumes_armed_in_its_mode_with_its_home():
    clock = _hovering()
    kept = clock.commander.kept_state()
    restarted = Commander({"COM_FAIL_ACT_T": 0.0})
    restarted.resume(kept, clock.t)
    clock.commander = restarted
    clock.step(1.0)
    assert clock.status.arming_state == NS.ARMING_STATE_ARMED
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    assert restarted.home is not None and restarted.home.position == (0.0, 0.0, 0.0)
    assert "Commander restarted: resuming armed in Hold" in clock.events


@pytest.mark.parametrize(
    "kept",
    [{}, {"intended_nav_state": 999}, {"intended_nav_state": 4, "armed_time_us": "x", "takeoff_time_us": 0}],
)
def test_a_kept_state_that_is_not_the_commanders_is_refused(kept):
    with pytest.raises(ValueError):
        Commander().resume(kept, 0)


def test_the_land_detector_of_a_commander_restarted_in_the_air_starts_flying():
    detector = MulticopterLandDetector()
    assert detector.state.landed
    detector.resume_in_air()
    assert not detector.state.landed and not detector.state.maybe_landed and not detector.state.ground_contact


def test_a_late_output_is_noticed_before_it_is_silent():
    monitor = ControlChainMonitor()
    _all_seen(monitor, 0)
    monitor.update(0, True, HOLD)
    assert not monitor.late
    assert monitor.update(STALE_US + 1, True, HOLD) == [] and monitor.late
    _all_seen(monitor, STALE_US + 2)
    monitor.update(STALE_US + 2, True, HOLD)
    assert not monitor.late


def test_a_commander_restarted_after_a_termination_keeps_the_vehicle_terminated():
    clock = _hovering()
    _keep_alive(clock, 0.1, but="mc_rate_control")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION
    restarted = Commander({"COM_FAIL_ACT_T": 0.0})
    restarted.resume(clock.commander.kept_state(), clock.t)
    clock.commander = restarted
    clock.step(1.0)
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION and clock.last.actuator_armed.termination


def test_a_terminated_vehicle_on_the_ground_disarms_and_may_fly_again():
    clock = _hovering()
    _keep_alive(clock, 0.1, but="mc_rate_control")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_TERMINATION
    assert clock.send(C.disarm_command()).result != 0  # still in the air: not landed
    clock.position, clock.landed = (0.0, 0.0, 0.0), True  # fallen, at rest
    _keep_alive(clock, 0.5, but="")
    assert clock.send(C.disarm_command()).result == 0
    clock.step()
    assert "Flight termination cleared: disarmed on the ground" in clock.events
    assert clock.status.nav_state != NS.NAVIGATION_STATE_TERMINATION and not clock.last.actuator_armed.termination
    assert clock.send(C.arm_command()).result == 0
    clock.step()
    assert clock.status.arming_state == NS.ARMING_STATE_ARMED


def test_a_terminated_vehicle_disarmed_by_force_in_the_air_may_fly_again_once_on_the_ground():
    clock = _hovering()
    _keep_alive(clock, 0.1, but="mc_att_control")
    assert clock.send(C.disarm_command(force=True)).result == 0  # still falling: the operator's word
    clock.step()
    assert clock.status.arming_state == NS.ARMING_STATE_DISARMED
    assert clock.send(C.arm_command()).result != 0
    clock.step()
    assert "Arming denied: flight termination is latched" in clock.events
    clock.position, clock.landed = (0.0, 0.0, 0.0), True  # at rest on the ground
    _keep_alive(clock, 0.2, but="")
    assert "Flight termination cleared: disarmed on the ground" in clock.events
    assert clock.status.nav_state != NS.NAVIGATION_STATE_TERMINATION
    assert clock.send(C.arm_command()).result == 0


def test_a_stalled_commander_catches_up_before_it_judges_its_inputs():
    clock = _hovering()
    stopped_at = clock.t
    clock.t += 3_000_000  # the commander's process stopped 3 s (SIGSTOP, a starved machine)
    stale = healthy(stopped_at, clock.position, False)  # what it read before the stop, delivered first
    clock.last = clock.commander.update(clock.t, stale)
    clock.events.extend(clock.last.events)
    assert "Commander stalled for 3.0 s: catching up" in clock.events
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER and not clock.status.failsafe
    _keep_alive(clock, 0.5, but="")
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER and not clock.status.failsafe
    _keep_alive(clock, 0.2, but="flight_mode_manager")  # caught up: a module silent now is named
    assert clock.status.control_lost_modules == ["flight_mode_manager"]


def test_with_an_external_autopilot_the_chain_is_not_the_stacks_to_watch():
    clock = _hovering()
    clock.commander.set_params({"COM_EXT_AP": 1})
    _keep_alive(clock, 0.5, but="attitude_estimator_q")
    assert clock.status.control_lost_modules == []
