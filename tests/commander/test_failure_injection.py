"""Commander: the inject-failure command, inputs taken before commands (``set_inputs``), and home position."""

from __future__ import annotations

import math

import pytest

from stack.commander import commands as C
from stack.commander.state_machine import Commander, CommanderOutputs
from stack.msg.system import VehicleCommand
from stack.msg.system import VehicleCommandAck as ACK
from stack.msg.system import VehicleStatus as NS
from tests.commander.helpers import REF, healthy, make_clock

CMD = VehicleCommand
NAN = math.nan
DISABLED = "Failure injection is disabled (SYS_FAILURE_EN 0)"


def inject(unit: float = CMD.FAILURE_UNIT_SENSOR_GPS, kind: float = CMD.FAILURE_TYPE_OFF) -> VehicleCommand:
    return CMD(
        command=CMD.VEHICLE_CMD_INJECT_FAILURE,
        param1=float(unit),
        param2=float(kind),
        source_system=42,
        source_component=190,
    )


def _state(clock):
    s = clock.step().vehicle_status
    return (s.arming_state, s.nav_state, s.nav_state_user_intention, clock.last.failsafe_action, clock.last.home)


# ---------------------------------------------------------------------------------------------- inject failure


def test_inject_failure_is_denied_with_a_reason_when_sys_failure_en_is_0():
    clock = make_clock()
    before = _state(clock)
    ack = clock.send(inject())
    assert (ack.command, ack.result, ack.reason, ack.result_param2) == (
        CMD.VEHICLE_CMD_INJECT_FAILURE,
        ACK.VEHICLE_CMD_RESULT_DENIED,
        DISABLED,
        0,
    )
    assert (ack.target_system, ack.target_component) == (42, 190)
    assert _state(clock) == before
    assert DISABLED in clock.events


def test_the_disabled_reason_comes_before_any_parameter_check():
    assert make_clock().send(inject(NAN, -1.0)).reason == DISABLED


@pytest.mark.parametrize("kind", [CMD.FAILURE_TYPE_OFF, CMD.FAILURE_TYPE_OK])
def test_gps_failure_injection_is_accepted_when_enabled_and_changes_no_state(kind):
    clock = make_clock(SYS_FAILURE_EN=1)
    before = _state(clock)
    ack = clock.send(inject(CMD.FAILURE_UNIT_SENSOR_GPS, kind))
    assert (ack.result, ack.reason) == (ACK.VEHICLE_CMD_RESULT_ACCEPTED, "")
    assert _state(clock) == before
    assert f"Failure injected: unit 4, type {kind}" in clock.events


def test_failure_injection_is_accepted_in_flight_without_touching_the_flight():
    clock = make_clock(SYS_FAILURE_EN=1)
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -10.0))
    clock.send(C.hold_command())
    before = _state(clock)
    assert clock.send(inject()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert _state(clock) == before
    assert before[0] == NS.ARMING_STATE_ARMED and before[1] == NS.NAVIGATION_STATE_AUTO_LOITER


def test_any_unit_and_type_are_accepted_the_simulator_decides_what_it_simulates():
    clock = make_clock(SYS_FAILURE_EN=1)
    assert clock.send(inject(CMD.FAILURE_UNIT_SENSOR_GYRO, 7.0)).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED


@pytest.mark.parametrize(
    ("unit", "kind", "param", "shown"),
    [
        (NAN, 1.0, 1, "nan"),
        (math.inf, 1.0, 1, "inf"),
        (4.5, 1.0, 1, "4.5"),
        (-1.0, 1.0, 1, "-1"),
        (4.0, NAN, 2, "nan"),
        (4.0, 0.25, 2, "0.25"),
        (4.0, -2.0, 2, "-2"),
    ],
)
def test_malformed_inject_failure_is_denied_naming_the_parameter(unit, kind, param, shown):
    clock = make_clock(SYS_FAILURE_EN=1)
    ack = clock.send(inject(unit, kind))
    assert (ack.result, ack.result_param2) == (ACK.VEHICLE_CMD_RESULT_DENIED, param)
    assert ack.reason == f"Failure injection: param{param} must be a non-negative integer, got {shown}"


def test_sys_failure_en_takes_effect_when_changed():
    commander = Commander()
    commander.update(1_000_000, healthy(1_000_000))
    assert commander.handle_command(inject(), 1_000_000).result == ACK.VEHICLE_CMD_RESULT_DENIED
    commander.set_params({"SYS_FAILURE_EN": 1})
    assert commander.handle_command(inject(), 1_000_000).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    commander.set_params({"SYS_FAILURE_EN": 0})
    assert commander.handle_command(inject(), 1_000_000).reason == DISABLED


# ---------------------------------------------------------------------------------------------- set_inputs


def test_a_command_is_judged_on_the_inputs_set_before_it_not_the_last_cycle():
    t = 1_000_000
    commander = Commander({"COM_FAIL_ACT_T": 0.0})
    commander.update(t, healthy(t, local_position=None))  # last cycle: no position yet
    commander.handle_command(C.set_mode_command("posctl"), t)
    t += 10_000
    refused = commander.handle_command(C.arm_command(), t)
    assert refused.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert refused.reason.startswith("Arming denied: Position mode requires")
    commander.set_inputs(t, healthy(t, position=(2.0, 3.0, 0.0)))
    assert commander.handle_command(C.arm_command(), t).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert commander.armed and commander.home is not None
    assert commander.home.position == (2.0, 3.0, 0.0)


def test_a_mode_change_is_refused_on_a_position_lost_since_the_last_cycle():
    clock = make_clock()
    clock.send(C.arm_command())
    clock.fly_to((0.0, 0.0, -10.0))
    clock.commander.set_inputs(clock.t, healthy(clock.t, (0.0, 0.0, -10.0), landed=False, local_position=None))
    ack = clock.send(C.hold_command())
    assert ack.result == ACK.VEHICLE_CMD_RESULT_TEMPORARILY_REJECTED
    assert ack.reason == "Switching to Hold is currently not possible: requires a valid local position estimate"


def test_set_inputs_runs_no_cycle():
    t = 1_000_000
    commander = Commander()
    first = commander.update(t, healthy(t, local_position=None))
    commander.set_inputs(t + 10_000, healthy(t + 10_000))
    assert commander.home is None  # home is set by the cycle, not by reading the inputs
    assert commander.nav_state == first.vehicle_status.nav_state and not commander.armed
    out = commander.update(t + 10_000, healthy(t + 10_000))
    assert out.home is not None and out.home.position == (0.0, 0.0, 0.0)


# ---------------------------------------------------------------------------------------------- home position


class Ground:
    """A commander stepped at 100 Hz with the inputs of each call (helpers.Clock's first cycle already has a
    position, and so a home)."""

    def __init__(self) -> None:
        self.commander = Commander({"COM_FAIL_ACT_T": 0.0})
        self.t = 1_000_000
        self.events: list[str] = []

    def step(self, seconds: float = 0.01, position=(0.0, 0.0, 0.0), landed: bool = True, **fields) -> CommanderOutputs:
        out = None
        for _ in range(max(round(seconds / 0.01), 1)):
            self.t += 10_000
            out = self.commander.update(self.t, healthy(self.t, position, landed, **fields))
            self.events.extend(out.events)
        assert out is not None
        return out


def test_home_is_set_when_the_position_first_becomes_valid_on_the_ground_before_arming():
    ground = Ground()
    assert ground.step(0.5, local_position=None).home is None
    out = ground.step(position=(1.0, 2.0, 0.0))
    assert out.home.position == (1.0, 2.0, 0.0)
    assert out.home.alt == pytest.approx(REF[2]) and out.home.lat == pytest.approx(REF[0], abs=1e-4)
    assert any(e.startswith("Home set at N 1.0 m, E 2.0 m") for e in ground.events)
    assert out.vehicle_status.arming_state == NS.ARMING_STATE_DISARMED


def test_home_is_not_moved_while_disarmed_on_the_ground():
    ground = Ground()
    ground.step(position=(1.0, 2.0, 0.0))
    assert ground.step(2.0, position=(8.0, -3.0, 0.0)).home.position == (1.0, 2.0, 0.0)


def test_home_is_not_set_from_a_position_in_the_air():
    ground = Ground()
    assert ground.step(0.5, position=(0.0, 0.0, -20.0), landed=False).home is None
    assert ground.step(position=(3.0, 0.0, 0.0)).home.position == (3.0, 0.0, 0.0)


@pytest.mark.parametrize("landed", [True, False])
def test_home_is_re_set_at_arming_where_the_vehicle_is_then(landed):
    clock = make_clock()
    assert clock.last.home.position == (0.0, 0.0, 0.0)
    clock.position = (8.0, -3.0, -0.2)  # carried to the take-off spot
    clock.landed = landed  # arming re-sets home whatever the land detector says (the cycle needs landed)
    clock.step()
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.commander.home.position == (8.0, -3.0, -0.2)
    assert clock.commander.home.alt == pytest.approx(REF[2] + 0.2)


def test_home_stays_in_flight_and_moves_to_the_landing_spot_at_the_next_arming():
    clock = make_clock(COM_DISARM_LAND=-1.0)
    clock.send(C.arm_command())
    clock.fly_to((30.0, 0.0, -10.0))
    assert clock.step(1.0).home.position == (0.0, 0.0, 0.0)
    clock.position, clock.landed = (30.0, 5.0, 0.0), True
    assert clock.step(1.0).home.position == (0.0, 0.0, 0.0)  # landed but still armed
    clock.send(C.disarm_command())
    assert clock.step().home.position == (0.0, 0.0, 0.0)  # disarmed: the first home is kept
    clock.send(C.arm_command())
    assert clock.step().home.position == (30.0, 5.0, 0.0)


def test_arming_without_a_position_keeps_the_previous_home():
    clock = make_clock()
    clock.step()
    home = clock.last.home
    assert home is not None
    clock.overrides = {"local_position": None}
    clock.send(C.set_mode_command("stabilized"))
    clock.step()
    assert clock.send(C.arm_command()).result == ACK.VEHICLE_CMD_RESULT_ACCEPTED
    assert clock.step().home == home
    clock.landed = False
    ack = clock.send(C.return_command())
    assert ack.reason == "Switching to Return is currently not possible: requires a valid local position estimate"
