"""The control chain on the RotorS profiles: RotorS' controller and joystick interface are watched in place of
PX4's attitude loop, rate loop and allocator, whose outputs they share or leave unpublished."""

from stack.commander.control_chain import OUTPUTS, SILENCE_US, ControlChainMonitor, Loss
from stack.commander.modes import control_mode
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleStatus as NS

HOLD = control_mode(NS.NAVIGATION_STATE_AUTO_LOITER, True)
ROTORS_MODE = control_mode(NS.NAVIGATION_STATE_EXTERNAL1, True)
COMMON = (
    "simulator", "attitude_estimator_q", "local_position_estimator", "commander", "mc_hover_thrust_estimator",
    "flight_mode_manager", "mc_pos_control",
)
ROTORS_PROFILE = (*COMMON, "roll_pitch_yawrate_thrust_controller", "rotors_joy_interface")
PX4_PROFILE = (*COMMON, "mc_att_control", "mc_rate_control", "control_allocator")


def _running(modules: tuple[str, ...]) -> ControlChainMonitor:
    monitor = ControlChainMonitor()
    for module in modules:
        monitor.module_alive(module)
    for topic in OUTPUTS:
        monitor.output_seen(topic, 0)
    return monitor


def _silent(monitor: ControlChainMonitor, topic: str, t: int, mode) -> set[tuple[str, Loss, bool]]:
    for other in OUTPUTS:
        if other != topic:
            monitor.output_seen(other, t)
    return {(f.module, f.loss, f.dead) for f in monitor.update(t, True, mode)}


def test_the_shared_output_names_the_controller_the_profile_runs():
    monitor = _running(ROTORS_PROFILE)
    assert monitor.update(0, True, HOLD) == []
    faults = _silent(monitor, ORB_ID.actuator_motors, SILENCE_US + 1, HOLD)
    assert faults == {("roll_pitch_yawrate_thrust_controller", Loss.ATTITUDE_CONTROL, False)}
    monitor = _running(PX4_PROFILE)
    monitor.update(0, True, HOLD)
    faults = _silent(monitor, ORB_ID.actuator_motors, SILENCE_US + 1, HOLD)
    assert faults == {("control_allocator", Loss.ATTITUDE_CONTROL, False)}


def test_a_module_the_profile_does_not_run_is_not_watched_whatever_published_its_output():
    """An Offboard rate setpoint is mc_att_control's output; on a RotorS profile it never comes back in Hold."""
    monitor = _running(ROTORS_PROFILE)
    monitor.update(0, True, HOLD)
    assert _silent(monitor, ORB_ID.vehicle_rates_setpoint, 10 * SILENCE_US, HOLD) == set()


def test_the_joystick_interface_is_watched_in_the_rotors_mode_only():
    monitor = _running(ROTORS_PROFILE)
    monitor.update(0, True, ROTORS_MODE)
    assert _silent(monitor, ORB_ID.roll_pitch_yawrate_thrust_setpoint, 10 * SILENCE_US, HOLD) == set()
    monitor.update(10 * SILENCE_US, True, ROTORS_MODE)
    faults = _silent(monitor, ORB_ID.roll_pitch_yawrate_thrust_setpoint, 11 * SILENCE_US + 1, ROTORS_MODE)
    assert faults == {("rotors_joy_interface", Loss.ATTITUDE_CONTROL, False)}


def test_a_dead_rotors_controller_is_known_at_once():
    monitor = _running(ROTORS_PROFILE)
    monitor.module_died("roll_pitch_yawrate_thrust_controller")
    faults = monitor.update(10, True, HOLD)
    assert [(f.module, f.dead) for f in faults] == [("roll_pitch_yawrate_thrust_controller", True)]
