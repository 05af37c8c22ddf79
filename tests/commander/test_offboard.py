"""The commander's Offboard checks: the offboard signal's proof of life (COM_OF_LOSS_T), the control flags of
each setpoint type, which commands ask for Offboard, and the refusal without a signal."""

import math

import pytest

from stack.commander import offboard
from stack.commander.modes import MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
from stack.mavlink.px4_modes import AutoSubMode, MainMode
from stack.msg.system import OffboardControlMode, VehicleCommand, VehicleCommandAck, VehicleControlMode, VehicleStatus

CMD = VehicleCommand
NS = VehicleStatus
LOSS_S = 1.0
NOW = 10_000_000
FLAG_FIELDS = [f for f in VehicleControlMode.__struct_fields__ if f.startswith("flag_control_")]


def ocm(age_us: int = 0, **setpoints: bool) -> OffboardControlMode:
    return OffboardControlMode(timestamp=NOW - age_us, **setpoints)


def set_mode(main: float, sub: float = math.nan, base: float = MAV_MODE_FLAG_CUSTOM_MODE_ENABLED) -> VehicleCommand:
    return CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=base, param2=main, param3=sub, source_system=7,
               source_component=190)


def test_a_fresh_signal_is_present_up_to_com_of_loss_t_and_not_after():
    assert offboard.signal_present(ocm(0, position=True), NOW, LOSS_S)
    assert offboard.signal_present(ocm(1_000_000, position=True), NOW, LOSS_S)
    assert not offboard.signal_present(ocm(1_000_001, position=True), NOW, LOSS_S)
    assert offboard.signal_present(ocm(1_000_001, position=True), NOW, 2.0)


def test_no_signal_at_all_is_no_signal():
    assert not offboard.signal_present(None, NOW, LOSS_S)
    assert offboard.control_flags_now(None, NOW, LOSS_S) is None


def test_a_stale_signal_gives_no_control_flags():
    assert offboard.control_flags_now(ocm(2_000_000, velocity=True), NOW, LOSS_S) is None
    assert offboard.control_flags_now(ocm(500_000, velocity=True), NOW, LOSS_S) is not None


def enabled(flags: dict[str, bool]) -> set[str]:
    """The loops a flag set turns on, by their short names (``flag_control_position_enabled`` → position)."""
    mode = VehicleControlMode(**flags)
    on = {f.removeprefix("flag_control_").removesuffix("_enabled") for f in FLAG_FIELDS if getattr(mode, f)}
    return on | ({"mc_position"} if mode.flag_multicopter_position_control_enabled else set())


POSITION_CHAIN = {"offboard", "mc_position", "acceleration", "attitude", "rates", "allocation"}


@pytest.mark.parametrize(
    ("setpoint", "loops"),
    [
        ("position", POSITION_CHAIN | {"position", "velocity", "altitude", "climb_rate"}),
        ("velocity", POSITION_CHAIN | {"velocity", "climb_rate"}),
        ("acceleration", POSITION_CHAIN),
        ("attitude", {"offboard", "attitude", "rates", "allocation"}),
        ("body_rate", {"offboard", "rates", "allocation"}),
        ("thrust_and_torque", {"offboard", "allocation"}),
        ("direct_actuator", {"offboard"}),
    ],
)
def test_each_setpoint_type_runs_the_loops_below_it(setpoint, loops):
    assert enabled(offboard.control_flags_now(ocm(**{setpoint: True}), NOW, LOSS_S)) == loops


def test_the_highest_setpoint_type_given_decides():
    both = offboard.control_flags(ocm(position=True, attitude=True, body_rate=True))
    assert both == offboard.control_flags(ocm(position=True))


@pytest.mark.parametrize(
    ("cmd", "wanted"),
    [
        (CMD(command=CMD.VEHICLE_CMD_SET_NAV_STATE, param1=float(NS.NAVIGATION_STATE_OFFBOARD)), True),
        (CMD(command=CMD.VEHICLE_CMD_SET_NAV_STATE, param1=float(NS.NAVIGATION_STATE_POSCTL)), False),
        (set_mode(MainMode.OFFBOARD), True),
        (set_mode(MainMode.OFFBOARD, 0.0), True),
        (set_mode(MainMode.POSCTL), False),
        (set_mode(MainMode.AUTO, AutoSubMode.LOITER), False),
        (set_mode(MainMode.OFFBOARD, base=0.0), False),  # without CUSTOM_MODE_ENABLED param2 means nothing
        (set_mode(math.nan), False),
        (set_mode(MainMode.OFFBOARD, base=math.nan), False),
        # Infinite parameters are no request, and never an exception (it would lose the cycle's other commands).
        (set_mode(MainMode.OFFBOARD, base=math.inf), False),
        (set_mode(math.inf), False),
        (set_mode(-math.inf), False),
        (set_mode(MainMode.OFFBOARD, math.inf), True),
        (CMD(command=CMD.VEHICLE_CMD_COMPONENT_ARM_DISARM, param1=1.0), False),
    ],
)
def test_which_commands_ask_for_offboard(cmd, wanted):
    assert offboard.requests_offboard(cmd) is wanted


def test_asking_for_offboard_without_a_signal_is_refused_to_the_sender():
    ack = offboard.refusal(set_mode(MainMode.OFFBOARD), None, NOW, LOSS_S)
    assert ack is not None
    assert ack.result == VehicleCommandAck.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert (ack.command, ack.target_system, ack.target_component) == (CMD.VEHICLE_CMD_DO_SET_MODE, 7, 190)
    assert ack.reason == offboard.NO_SIGNAL_REASON
    stale = offboard.refusal(set_mode(MainMode.OFFBOARD), ocm(1_500_000, body_rate=True), NOW, LOSS_S)
    assert stale is not None and stale.result == VehicleCommandAck.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED


def test_with_a_signal_or_for_another_mode_the_commander_decides():
    assert offboard.refusal(set_mode(MainMode.OFFBOARD), ocm(100_000, velocity=True), NOW, LOSS_S) is None
    assert offboard.refusal(set_mode(MainMode.POSCTL), None, NOW, LOSS_S) is None
