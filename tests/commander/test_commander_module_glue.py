"""The commander module on a bench: what it publishes and when (on change, at 2 Hz, the land detector at 50 Hz with
its 1 Hz republication), commands answered or ignored, parameters reaching the commander and the land detector
(PX4 src/modules/commander/Commander.cpp, src/modules/land_detector/LandDetector.cpp)."""

import pytest

from stack.commander.land_detector import MulticopterLandDetector
from stack.commander.module import REPUBLISH_US, CommanderModule
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import VehicleThrustSetpoint
from stack.msg.system import VehicleCommand, VehicleCommandAck, VehicleStatus
from tests.support.bench import ModuleBench, stand_in

DT = 0.01
STATE_TOPICS = (ORB_ID.actuator_armed, ORB_ID.navigation_request, ORB_ID.vehicle_status, ORB_ID.vehicle_control_mode)


def run_for(bench: ModuleBench, seconds: float) -> None:
    for _ in range(round(seconds / DT)):
        bench.run(None, DT)


def test_the_vehicles_state_goes_out_on_the_first_run_then_at_two_hertz_stamped_now():
    bench = ModuleBench(CommanderModule)
    bench.run(None, DT)
    for topic in STATE_TOPICS:
        (msg,) = bench.sent(topic)
        assert msg.timestamp == bench.now
    run_for(bench, 1.0)
    assert len(bench.sent(ORB_ID.vehicle_status)) == 1 + round(1e6 / REPUBLISH_US)
    assert bench.sent(ORB_ID.home_position) == []  # no home before a position


def test_land_detection_at_fifty_hertz_published_on_change_or_every_second(monkeypatch):
    detected = stand_in(monkeypatch, MulticopterLandDetector, "update", through=True)
    bench = ModuleBench(CommanderModule)
    run_for(bench, 2.0)
    assert [now for now, _ in detected[:3]] == [10_000, 20_000, 40_000]  # the first tick of each 20 ms
    assert len(detected) == 1 + 2.0 / 0.02
    published = bench.sent(ORB_ID.vehicle_land_detected)
    # unchanged: again on the first land tick a second (LAND_DETECTED_REPUBLISH_US) later
    assert [m.timestamp for m in published] == [10_000, 1_020_000]
    assert published[0].landed


def test_a_command_is_acknowledged_and_one_for_another_vehicle_ignored():
    bench = ModuleBench(CommanderModule)
    bench.put(ORB_ID.vehicle_command, VehicleCommand(command=VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM,
                                                     param1=1.0))
    bench.run(None, DT)
    (ack,) = bench.sent(ORB_ID.vehicle_command_ack)
    assert ack.command == VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM
    assert ack.result != VehicleCommandAck.VEHICLE_CMD_RESULT_ACCEPTED  # no estimate yet: arming refused
    assert any(ack.reason in log.text for log in bench.sent(ORB_ID.mavlink_log))  # the operator is told why
    bench.put(ORB_ID.vehicle_command, VehicleCommand(command=VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM,
                                                     param1=1.0, target_system=42))
    bench.run(None, DT)
    assert len(bench.sent(ORB_ID.vehicle_command_ack)) == 1 and bench.module.commander.ignored_commands == 1


def test_the_land_detector_sees_no_throttle_in_termination(monkeypatch):
    bench = ModuleBench(CommanderModule)
    bench.put(ORB_ID.vehicle_thrust_setpoint, VehicleThrustSetpoint(xyz=(0.0, 0.0, -0.6)))
    seen = stand_in(monkeypatch, MulticopterLandDetector, "update", through=True)
    bench.run(None, DT)
    assert seen[-1][1].throttle == pytest.approx(0.6)
    assert seen[-1][1].climb_rate_control is False  # manual mode at start
    monkeypatch.setattr(bench.module.commander, "nav_state", VehicleStatus.NAVIGATION_STATE_TERMINATION)
    run_for(bench, 0.02)
    assert seen[-1][1].throttle == 0.0


def test_a_parameter_change_reaches_the_commander_and_the_land_detector(monkeypatch):
    bench = ModuleBench(CommanderModule)
    detector = stand_in(monkeypatch, MulticopterLandDetector, "set_params")
    bench.set_param("COM_DISARM_LAND", 5.0)
    assert bench.module.commander._p.auto_disarm.com_disarm_land == 5.0
    assert detector[-1][0]["COM_DISARM_LAND"] == 5.0
