from stack.commander import commands as C
from stack.commander.state_machine import ArmDisarmReason, Commander
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import Clock, make_clock


def _hovering(**params):
    clock = make_clock(**params)
    clock.send(C.takeoff_command(5.0))
    clock.fly_to((0.0, 0.0, -5.0))
    assert clock.status.nav_state == NS.NAVIGATION_STATE_AUTO_LOITER
    return clock


def test_land_then_auto_disarm_after_com_disarm_land():
    clock = _hovering()
    assert clock.send(C.land_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.fly_to((0.0, 0.0, -2.0)).vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_LAND
    clock.position = (0.0, 0.0, 0.0)
    clock.landed = True
    assert clock.step(1.95).vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    out = clock.step(0.1)
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED
    assert out.vehicle_status.latest_disarming_reason == ArmDisarmReason.AUTO_DISARM_LAND
    assert out.vehicle_status.takeoff_time == 0
    assert "Disarmed (auto_disarm_land)" in clock.events


def test_a_bounce_restarts_the_disarm_timer():
    clock = _hovering()
    clock.send(C.land_command())
    clock.landed = True
    clock.step(1.5)
    clock.landed = False
    clock.step()
    clock.landed = True
    assert clock.step(1.9).vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    assert clock.step(0.2).vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_no_auto_disarm_when_landed_mid_mission():
    clock = make_clock()
    clock.overrides = {"mission_count": 3}
    clock.step()
    clock.send(C.mission_start_command(0))
    clock.fly_to((0.0, 0.0, -5.0))
    clock.landed = True
    assert clock.step(5.0).vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    clock.overrides["mission_finished"] = True
    assert clock.step(2.1).vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_return_mode_reaches_the_ground_and_disarms():
    clock = _hovering()
    clock.fly_to((20.0, 0.0, -10.0))
    assert clock.send(C.return_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().vehicle_status.nav_state == NS.NAVIGATION_STATE_AUTO_RTL
    clock.position = (0.0, 0.0, 0.0)
    clock.landed = True
    assert clock.step(2.1).vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_home_is_set_when_a_position_first_appears_on_the_ground():
    clock = Clock(Commander({"COM_FAIL_ACT_T": 0.0}), overrides={"local_position": None})
    clock.step()
    clock.send(C.set_mode_command("stabilized"))
    clock.send(C.arm_command())
    assert clock.step().home is None
    clock.position = (1.0, 2.0, 0.0)
    del clock.overrides["local_position"]
    assert clock.step().home.position == (1.0, 2.0, 0.0)
