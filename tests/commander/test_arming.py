import math

import pytest

from stack.commander import commands as C
from stack.commander.state_machine import ArmDisarmReason, Commander
from stack.msg.system import BatteryWarning, VehicleCommand
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import healthy, local_position, make_clock


def test_arming_refused_without_a_valid_attitude_estimate():
    clock = make_clock()
    clock.overrides = {"attitude_timestamp_us": 0}
    clock.step()
    ack = clock.send(C.arm_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Arming denied: attitude estimate invalid"
    assert ack.command == VehicleCommand.VEHICLE_CMD_COMPONENT_ARM_DISARM
    assert clock.step().vehicle_status.arming_state == NS.ARMING_STATE_DISARMED
    assert not clock.status.pre_flight_checks_pass


def test_arming_refused_with_a_stale_attitude_estimate():
    clock = make_clock()
    clock.overrides = {"attitude_timestamp_us": clock.t - 1_500_000}
    clock.step()
    assert "attitude" in clock.send(C.arm_command()).reason


def test_arming_refused_in_position_mode_without_a_local_position():
    clock = make_clock()
    assert clock.send(C.set_mode_command("posctl")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.overrides = {"local_position": None}
    clock.step()
    ack = clock.send(C.arm_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Arming denied: Position mode requires a local position estimate"
    # Stabilized needs no position: the same vehicle arms there.
    assert clock.send(C.set_mode_command("stabilized")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


@pytest.mark.parametrize(
    ("override", "reason"),
    [
        ({"gyro_timestamp_us": 0}, "Arming denied: no gyro data"),
        ({"baro_timestamp_us": 0}, "Arming denied: no barometer data"),
        ({"angular_velocity_timestamp_us": 0}, "Arming denied: no angular velocity estimate"),
        ({"attitude_q": (0.5, 0.0, 0.0, 0.0)}, "Arming denied: attitude estimate invalid"),
        ({"gps_fix_type": 2}, "Arming denied: no 3D GPS fix"),
        ({"battery_warning": BatteryWarning.CRITICAL}, "Arming denied: battery critically low"),
    ],
)
def test_prearm_check_reasons(override, reason):
    clock = make_clock()
    clock.send(C.set_mode_command("hold"))
    clock.overrides = override
    clock.step()
    ack = clock.send(C.arm_command())
    assert (ack.result, ack.reason) == (ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED, reason)


def test_low_battery_only_warns_and_gps_is_optional_without_a_position_mode():
    clock = make_clock()
    clock.overrides = {"battery_warning": BatteryWarning.LOW, "gps_timestamp_us": 0}
    clock.step()
    assert clock.send(C.set_mode_command("stabilized")).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_magnetometer_check_follows_sys_has_mag():
    clock = make_clock(SYS_HAS_MAG=0)
    clock.overrides = {"mag_timestamp_us": 0}
    clock.step()
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


def test_pre_flight_checks_rerun_at_10_hz_between_state_changes():
    """PX4 Commander.cpp: the arming checks run at 10 Hz (and at once on a state change), not every cycle."""
    clock = make_clock()
    clock.step(0.2)
    assert clock.status.pre_flight_checks_pass
    clock.overrides = {"baro_timestamp_us": clock.t - 1_500_000}
    clock.step(0.05)
    assert clock.status.pre_flight_checks_pass
    clock.step(0.05)
    assert not clock.status.pre_flight_checks_pass
    assert not clock.last.actuator_armed.ready_to_arm


def test_arming_accepted_when_healthy_sets_home_and_status():
    clock = make_clock()
    clock.position = (3.0, -2.0, -0.1)
    clock.step()
    assert clock.status.pre_flight_checks_pass
    assert clock.last.actuator_armed.ready_to_arm
    ack = clock.send(C.arm_command())
    assert (ack.result, ack.reason) == (ACK.VEHICLE_CMD_RESULT_ACCEPTED, "")
    out = clock.step()
    status = out.vehicle_status
    assert status.arming_state == NS.ARMING_STATE_ARMED
    assert status.armed_time == clock.t - clock.period
    assert status.latest_arming_reason == ArmDisarmReason.COMMAND_EXTERNAL
    assert out.actuator_armed.armed and out.vehicle_control_mode.flag_armed
    assert out.home.position == (3.0, -2.0, -0.1)
    assert out.home.alt == pytest.approx(489.5)
    assert math.isfinite(out.home.lat) and out.home.lat > 47.397742


def test_arm_when_armed_and_disarm_when_disarmed_are_accepted_without_change():
    clock = make_clock()
    assert clock.send(C.disarm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    clock.send(C.arm_command())
    armed_time = clock.step().vehicle_status.armed_time
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().vehicle_status.armed_time == armed_time


def test_forced_arm_skips_the_checks():
    commander = Commander()
    ack = commander.handle_command(C.arm_command(force=True), 1_000_000)
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert commander.armed
    assert commander.home is None


def test_disarm_refused_in_the_air_unless_forced():
    clock = make_clock()
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -5.0))
    ack = clock.send(C.disarm_command())
    assert (ack.result, ack.reason) == (ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED, "Disarming denied: not landed")
    assert clock.step().vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    assert clock.send(C.disarm_command(force=True)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_disarm_on_the_ground():
    clock = make_clock()
    clock.send(C.arm_command())
    clock.step()
    ack = clock.send(C.disarm_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    out = clock.step()
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED
    assert out.vehicle_status.latest_disarming_reason == ArmDisarmReason.COMMAND_EXTERNAL
    assert not out.actuator_armed.armed


def test_return_and_land_modes_cannot_be_selected_disarmed_nor_armed_in():
    clock = make_clock()
    ack = clock.send(C.return_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Switching to Return is currently not possible: the vehicle is disarmed"
    commander = Commander()
    commander.update(1, healthy(1))
    commander.user_intended_nav_state = NS.NAVIGATION_STATE_AUTO_LAND
    assert commander.handle_command(C.arm_command(), 1).reason == (
        "Arming denied: not possible in Land mode, switch mode first"
    )


def test_auto_disarm_preflight_after_com_disarm_prflt():
    clock = make_clock()
    clock.send(C.set_mode_command("hold"))
    clock.send(C.arm_command())
    assert clock.step(9.9).vehicle_status.arming_state == NS.ARMING_STATE_ARMED
    out = clock.step(0.11)
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED
    assert out.vehicle_status.latest_disarming_reason == ArmDisarmReason.AUTO_DISARM_PREFLIGHT


def test_auto_disarm_preflight_disabled():
    clock = make_clock(COM_DISARM_PRFLT=0.0)
    clock.send(C.arm_command())
    assert clock.step(15.0).vehicle_status.arming_state == NS.ARMING_STATE_ARMED


def test_local_position_message_fields_feed_home_yaw():
    commander = Commander()
    inputs = healthy(1_000_000)
    inputs.local_position = local_position(1_000_000, heading=1.2)
    commander.update(1_000_000, inputs)
    commander.handle_command(C.arm_command(), 1_000_000)
    assert commander.home.yaw == pytest.approx(1.2)
