"""What the pixhawk module decides (stack.pixhawk.plant): stream rates, command transactions, the hand-off."""

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.pixhawk import plant
from stack.pixhawk.plant import Control, Handoff

ARMED = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED | mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
DISARMED = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
STANDBY = mavlink2.MAV_STATE_STANDBY
ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED
SET_MODE = mavlink2.MAV_CMD_DO_SET_MODE
ARM = mavlink2.MAV_CMD_COMPONENT_ARM_DISARM


# -- streams ---------------------------------------------------------------------------------------------


def test_the_imu_rate_fits_the_link():
    udp = plant.stream_plan(None, autopilot_estimate=False)
    assert udp[0].msg_class is mavlink2.MAVLink_highres_imu_message and udp[0].hz == 250.0
    # 921600 baud carries 92160 B/s each way: 250 Hz of HIGHRES_IMU (75 B frames) and the rest fit in half.
    uart = plant.stream_plan(921600, autopilot_estimate=True)
    assert uart[0].hz == 250.0
    assert sum(s.bytes_per_s for s in uart) <= plant.INBOUND_SHARE * plant.link_budget_bytes_per_s(921600)
    slow = plant.stream_plan(115200, autopilot_estimate=False)
    assert plant.IMU_RATE_MIN_HZ <= slow[0].hz < 100.0
    assert sum(s.bytes_per_s for s in slow) == pytest.approx(
        plant.INBOUND_SHARE * plant.link_budget_bytes_per_s(115200)
    )
    off = {s.msg_class: s for s in udp if s.hz == 0}
    assert mavlink2.MAVLink_attitude_message in off and off[mavlink2.MAVLink_attitude_message].interval_us == -1


def test_message_interval_command():
    stream = plant.Stream(mavlink2.MAVLink_highres_imu_message, 250.0)
    c = plant.message_interval_command(stream)
    assert c.command == mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL and c.params[:2] == (105.0, 4000.0)


# -- command transactions --------------------------------------------------------------------------------


def test_a_command_is_resent_with_confirmation_until_acknowledged():
    cmds = plant.Commands(timeout_us=100, attempts=3)
    cmds.start(plant.arm_command(True))
    assert [c.confirmation for c in cmds.due(0)] == [0]
    assert cmds.due(50) == []
    assert [c.confirmation for c in cmds.due(100)] == [1]
    cmds.on_ack(120, ARM, mavlink2.MAV_RESULT_IN_PROGRESS)  # working on it: wait a full timeout again
    assert cmds.due(200) == [] and cmds.busy(ARM)
    t = cmds.on_ack(210, ARM, ACCEPTED)
    assert t is not None and t.result == ACCEPTED and not cmds.busy(ARM)
    assert cmds.on_ack(220, ARM, ACCEPTED) is None  # a duplicate ACK finishes nothing


def test_an_unanswered_command_fails_after_its_attempts():
    cmds = plant.Commands(timeout_us=100, attempts=2)
    cmds.start(plant.set_mode_command(Px4Mode.OFFBOARD))
    assert len(cmds.due(0)) == 1 and len(cmds.due(100)) == 1 and cmds.due(200) == []
    (failed,) = cmds.finished
    assert failed.result is None and "no answer after 2 attempts" in failed.reason


def test_a_refusal_carries_the_autopilots_last_warning():
    cmds = plant.Commands()
    cmds.start(plant.arm_command(True))
    cmds.due(0)
    cmds.on_statustext(10, mavlink2.MAV_SEVERITY_INFO, "not a reason")
    cmds.on_statustext(20, mavlink2.MAV_SEVERITY_CRITICAL, "Arming denied: vehicle not landed")
    t = cmds.on_ack(30, ARM, mavlink2.MAV_RESULT_TEMPORARILY_REJECTED)
    assert t is not None and t.reason == "temporarily rejected: Arming denied: vehicle not landed"


def test_set_mode_command_is_px4s_custom_mode():
    c = plant.set_mode_command(Px4Mode.AUTO_LOITER)
    assert c.params[:3] == (1.0, 4.0, 3.0)


# -- the hand-off ----------------------------------------------------------------------------------------


def connected(now: int = 0, mode: Px4Mode = Px4Mode.POSCTL, armed: bool = False) -> Handoff:
    h = Handoff()
    h.on_connection(now, True)
    h.on_heartbeat(now, ARMED if armed else DISARMED, px4_modes.encode(mode), STANDBY)
    return h


def acknowledge(h: Handoff, now: int, sent: list[plant.CommandLong], result: int = ACCEPTED) -> None:
    for c in sent:
        h.on_ack(now, c.command, result)


def test_arming_switches_to_offboard_then_arms():
    h = connected()
    assert h.proof_of_life and not h.stream
    assert h.tick(1) == []  # the stack is disarmed: nothing to do
    h.on_stack_armed(True)
    assert h.stream and not h.proof_of_life
    (mode,) = h.tick(2)
    assert mode.command == SET_MODE and h.control is Control.TAKING_CONTROL
    acknowledge(h, 3, [mode])
    (arm,) = h.tick(4)
    assert arm.command == ARM and arm.params[0] == 1.0
    acknowledge(h, 5, [arm])
    assert h.tick(6) == [] and h.in_control and h.view.armed and h.view.offboard
    h.on_heartbeat(7, ARMED, px4_modes.encode(Px4Mode.OFFBOARD), mavlink2.MAV_STATE_ACTIVE)
    assert h.in_control and h.refusals == 0


def test_a_refused_arming_is_counted_with_its_reason_and_not_retried():
    h = connected(mode=Px4Mode.OFFBOARD)
    h.on_stack_armed(True)
    (arm,) = h.tick(1)
    h.on_statustext(2, mavlink2.MAV_SEVERITY_CRITICAL, "Arming denied: no offboard signal")
    acknowledge(h, 3, [arm], mavlink2.MAV_RESULT_DENIED)
    assert h.tick(4) == []
    assert h.refusals == 1 and h.refusal == "the Pixhawk refused to arm: denied: Arming denied: no offboard signal"
    h.on_stack_armed(False)
    h.tick(5)
    h.on_stack_armed(True)  # a new arming tries again
    assert [c.command for c in h.tick(6)] == [ARM]


def flying() -> Handoff:
    h = connected(mode=Px4Mode.OFFBOARD, armed=True)
    h.on_stack_armed(True)
    h.tick(1)
    assert h.in_control
    return h


def test_the_pixhawk_leaving_offboard_is_a_yield_until_a_new_mode_command():
    h = flying()
    h.on_heartbeat(10, ARMED, px4_modes.encode(Px4Mode.AUTO_LOITER), mavlink2.MAV_STATE_CRITICAL)
    assert h.tick(11) == [] and h.control is Control.YIELDED
    assert h.tick(12) == []  # it never takes Offboard back by itself
    assert h.stream  # but keeps the setpoints coming, which PX4 wants before Offboard
    h.on_stack_mode_command()
    (mode,) = h.tick(13)
    assert mode.command == SET_MODE and mode.params[1] == 6.0
    acknowledge(h, 14, [mode])
    h.tick(15)
    assert h.in_control


def test_a_link_gap_yields_and_the_next_heartbeat_decides():
    h = flying()
    h.on_connection(10, False)
    assert h.tick(11) == [] and h.control is Control.YIELDED and not h.stream
    h.on_connection(20, True)
    h.tick(21)
    assert h.control is Control.YIELDED  # what the Pixhawk did meanwhile, its next heartbeat says
    h.on_heartbeat(30, ARMED, px4_modes.encode(Px4Mode.OFFBOARD), mavlink2.MAV_STATE_ACTIVE)
    h.tick(31)
    assert h.in_control  # its failsafe cleared when the setpoints came back (PX4's Offboard loss does)


def test_commands_in_flight_survive_a_short_gap():
    h = connected()
    h.on_stack_armed(True)
    h.tick(0)
    h.on_connection(10, False)
    assert h.tick(300_000) == []
    h.on_connection(310_000, True)
    h.on_heartbeat(320_000, DISARMED, px4_modes.encode(Px4Mode.POSCTL), STANDBY)
    again = h.tick(330_000)
    assert [c.command for c in again] == [SET_MODE] and again[0].confirmation == 1


def test_the_stack_disarming_disarms_the_pixhawk_in_offboard_only():
    h = flying()
    h.on_stack_armed(False)
    (disarm,) = h.tick(10)
    assert disarm.command == ARM and disarm.params[0] == 0.0 and h.control is Control.IDLE
    assert not h.stream and not h.proof_of_life  # no thrust cut: a refused disarm leaves PX4's failsafe
    acknowledge(h, 11, [disarm], mavlink2.MAV_RESULT_DENIED)
    h.tick(12)
    assert h.refusals == 0 and any("refused to disarm" in e for e in h.events)
    pilot = connected(mode=Px4Mode.POSCTL, armed=True)  # a pilot flies it: left alone
    assert pilot.tick(1) == []


def test_a_disarm_while_arming_cancels_the_arming():
    h = connected(mode=Px4Mode.OFFBOARD)
    h.on_stack_armed(True)
    assert len(h.tick(1)) == 1
    h.on_stack_armed(False)
    assert h.tick(2) == [] and not h.commands.busy(ARM)
    assert h.commands.on_ack(3, ARM, ACCEPTED) is None  # a late ACK finishes nothing


@pytest.mark.parametrize(
    ("prearm", "status", "armable"),
    [(True, mavlink2.MAV_STATE_CRITICAL, True), (False, STANDBY, False), (None, STANDBY, True), (None, 4, False)],
)
def test_armable_follows_the_prearm_bit_else_standby(prearm, status, armable):
    h = Handoff()
    h.on_heartbeat(0, DISARMED, px4_modes.encode(Px4Mode.OFFBOARD), status)
    h.on_sys_status(prearm)
    assert h.view.armable is armable


def test_latency_percentiles():
    stats = plant.LatencyStats(window=100)
    for age in range(1, 101):
        stats.add(age)
    assert stats.percentile(50.0) == 51.0 and stats.percentile(99.0) == 100.0
