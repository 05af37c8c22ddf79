"""The simulated Pixhawk's commander: arming checks, mode changes, the Offboard signal and its loss, auto-disarm."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink

from stack.airframe.model import load_vehicle
from stack.commander.offboard import OffboardLossAction
from stack.mavlink.px4_modes import Px4Mode
from stack.params.param import ParamError
from stack.pixhawk_sim.commander import Condition, Px4Commander
from stack.pixhawk_sim.params import parameter_values, read_params_file

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
DENIED = mavlink.MAV_RESULT_DENIED
ON_GROUND = Condition(landed=True, maybe_landed=True, roll=0.0, pitch=0.0)
FLYING = Condition(landed=False, maybe_landed=False, roll=0.0, pitch=0.0)
S = 1_000_000


def commander(**overrides: object) -> Px4Commander:
    return Px4Commander(parameter_values(load_vehicle("sih_quad"), overrides))


def armed_in_offboard(c: Px4Commander, now: int = 0) -> None:
    c.offboard_setpoint(now)
    assert c.set_mode(Px4Mode.OFFBOARD, now).result == ACCEPTED
    assert c.arm_disarm(True, False, now, ON_GROUND).result == ACCEPTED
    c.take_notices()


def test_boots_in_position_mode_and_cannot_arm_there_without_rc() -> None:
    c = commander()
    assert c.mode is Px4Mode.POSCTL and not c.armed
    verdict = c.arm_disarm(True, False, 0, ON_GROUND)
    assert verdict.result == REJECTED
    assert "manual control" in verdict.reason
    assert [n.severity for n in c.take_notices()] == [mavlink.MAV_SEVERITY_CRITICAL]
    assert not c.armed


def test_offboard_needs_the_setpoint_stream_before_arming() -> None:
    c = commander()
    assert c.set_mode(Px4Mode.OFFBOARD, 0).result == ACCEPTED  # PX4 takes any mode while disarmed
    verdict = c.arm_disarm(True, False, 0, ON_GROUND)
    assert verdict.result == REJECTED and verdict.reason == "Arming denied: no offboard signal"
    c.offboard_setpoint(S)
    assert c.arm_disarm(True, False, S, ON_GROUND).result == ACCEPTED
    assert c.armed and c.mode is Px4Mode.OFFBOARD
    # Arming an armed vehicle is accepted and changes nothing, as PX4 answers it.
    assert c.arm_disarm(True, False, S, ON_GROUND).result == ACCEPTED


def test_armed_switch_to_offboard_needs_a_live_stream() -> None:
    c = commander()
    assert c.set_mode(Px4Mode.AUTO_LOITER, 0).result == ACCEPTED
    assert c.arm_disarm(True, False, 0, ON_GROUND).result == ACCEPTED
    verdict = c.set_mode(Px4Mode.OFFBOARD, 0)
    assert verdict.result == REJECTED and "no offboard signal" in verdict.reason
    c.offboard_setpoint(S)
    assert c.set_mode(Px4Mode.OFFBOARD, S + S // 2).result == ACCEPTED
    assert c.mode is Px4Mode.OFFBOARD


def test_arming_refused_in_the_air_tilted_or_in_land_unless_forced() -> None:
    c = commander()
    c.offboard_setpoint(0)
    c.set_mode(Px4Mode.OFFBOARD, 0)
    assert c.arm_disarm(True, False, 0, FLYING).reason == "Arming denied: vehicle not landed"
    tilted = Condition(True, True, math.radians(70.0), 0.0)
    assert c.arm_disarm(True, False, 0, tilted).reason == "Arming denied: attitude failure (roll)"
    pitched = Condition(True, True, 0.0, math.radians(-61.0))
    assert c.arm_disarm(True, False, 0, pitched).reason == "Arming denied: attitude failure (pitch)"
    c.set_mode(Px4Mode.AUTO_LAND, 0)
    assert c.arm_disarm(True, False, 0, ON_GROUND).result == REJECTED
    assert not c.armed
    assert c.arm_disarm(True, True, 0, tilted).result == ACCEPTED  # 21196: the checks are skipped
    assert c.armed


def test_modes_that_are_not_simulated_are_denied() -> None:
    c = commander()
    for mode in (Px4Mode.AUTO_MISSION, Px4Mode.AUTO_TAKEOFF, Px4Mode.AUTO_RTL, None):
        verdict = c.set_mode(mode, 0)
        assert verdict.result == DENIED
    assert c.user_mode is Px4Mode.POSCTL


def test_disarming_in_the_air_needs_the_force_code() -> None:
    c = commander()
    armed_in_offboard(c)
    verdict = c.arm_disarm(False, False, 0, FLYING)
    assert verdict.result == REJECTED and verdict.reason == "Disarming denied: not landed"
    assert c.armed
    assert c.arm_disarm(False, True, 0, FLYING).result == ACCEPTED
    assert not c.armed
    assert c.arm_disarm(False, False, 0, ON_GROUND).result == ACCEPTED  # already disarmed


@pytest.mark.parametrize(
    ("action", "mode"),
    [
        (OffboardLossAction.POSITION, Px4Mode.AUTO_LOITER),  # falls through to Hold without RC
        (OffboardLossAction.ALTITUDE, Px4Mode.AUTO_LOITER),
        (OffboardLossAction.STABILIZED, Px4Mode.AUTO_LOITER),
        (OffboardLossAction.HOLD, Px4Mode.AUTO_LOITER),
        (OffboardLossAction.LAND, Px4Mode.AUTO_LAND),
        (OffboardLossAction.TERMINATE, Px4Mode.TERMINATION),
    ],
)
def test_offboard_loss_flies_com_obl_rc_act_after_com_of_loss_t(action: OffboardLossAction, mode: Px4Mode) -> None:
    c = commander(COM_OBL_RC_ACT=int(action), COM_OF_LOSS_T=0.5)
    armed_in_offboard(c)
    c.update(S // 2, FLYING)
    assert c.mode is Px4Mode.OFFBOARD and not c.failsafe
    c.update(S // 2 + 4000, FLYING)
    assert c.mode is mode and c.failsafe
    assert c.user_mode is Px4Mode.OFFBOARD
    notices = c.take_notices()
    assert notices[-1].severity == mavlink.MAV_SEVERITY_CRITICAL
    assert "offboard signal lost" in notices[-1].text


def test_offboard_loss_with_disarm_action_disarms() -> None:
    c = commander(COM_OBL_RC_ACT=int(OffboardLossAction.DISARM))
    armed_in_offboard(c)
    c.update(2 * S, FLYING)
    assert not c.armed


def test_return_action_is_refused_as_a_parameter() -> None:
    with pytest.raises(ParamError):
        parameter_values(load_vehicle("sih_quad"), {"COM_OBL_RC_ACT": int(OffboardLossAction.RETURN)})


def test_the_failsafe_clears_when_the_stream_returns_and_offboard_resumes() -> None:
    c = commander()
    armed_in_offboard(c)
    c.update(2 * S, FLYING)
    assert c.mode is Px4Mode.AUTO_LOITER
    c.offboard_setpoint(3 * S)
    c.update(3 * S, FLYING)
    assert c.mode is Px4Mode.OFFBOARD and not c.failsafe
    assert c.take_notices()[-1].text == "Failsafe cleared: OFFBOARD"


def test_terminated_vehicle_cannot_be_armed_again() -> None:
    c = commander(COM_OBL_RC_ACT=int(OffboardLossAction.TERMINATE))
    armed_in_offboard(c)
    c.update(2 * S, FLYING)
    assert c.terminated
    c.arm_disarm(False, True, 2 * S, FLYING)
    c.offboard_setpoint(3 * S)
    c.update(3 * S, ON_GROUND)
    assert c.mode is Px4Mode.TERMINATION
    assert c.arm_disarm(True, False, 3 * S, ON_GROUND).result == REJECTED


def test_auto_disarm_after_landing_and_before_takeoff() -> None:
    c = commander(COM_DISARM_LAND=2.0, COM_DISARM_PRFLT=10.0)
    armed_in_offboard(c)
    for t in range(0, 10 * S, S // 10):
        c.offboard_setpoint(t)
        c.update(t, ON_GROUND)
        assert c.armed
    c.offboard_setpoint(10 * S + S // 10)
    c.update(10 * S + S // 10, ON_GROUND)
    assert not c.armed  # COM_DISARM_PRFLT: never took off

    armed_in_offboard(c, 20 * S)
    c.update(20 * S, FLYING)
    assert c.have_taken_off
    for t in range(21 * S, 23 * S, S // 10):
        c.offboard_setpoint(t)
        c.update(t, ON_GROUND)
        assert c.armed
    c.offboard_setpoint(23 * S)
    c.update(23 * S, ON_GROUND)
    assert not c.armed  # COM_DISARM_LAND after landing
    assert c.take_notices()[-1].text == "Disarmed (landed)"


def test_armed_in_a_mode_it_cannot_fly_it_holds() -> None:
    c = commander()
    assert c.arm_disarm(True, True, 0, ON_GROUND).result == ACCEPTED  # forced, in Position mode
    c.update(0, ON_GROUND)
    assert c.mode is Px4Mode.AUTO_LOITER and c.failsafe


def test_parameters_come_from_the_airframe_then_a_params_file_then_the_command_line(tmp_path) -> None:
    vehicle = load_vehicle("sih_quad")
    assert parameter_values(vehicle)["MPC_THR_HOVER"] == vehicle.airframe["MPC_THR_HOVER"]
    path = tmp_path / "profile.toml"
    path.write_text('[params]\nMC_ROLLRATE_K = 1.5\nATT_MAG_DECL = 3.2\n\n[[module]]\nmodule = "x"\n')
    used, ignored = read_params_file(path)
    assert used == {"MC_ROLLRATE_K": 1.5} and ignored == ["ATT_MAG_DECL"]
    values = parameter_values(vehicle, {**used, "COM_OF_LOSS_T": "0.5"})
    assert values["MC_ROLLRATE_K"] == 1.5 and values["COM_OF_LOSS_T"] == 0.5
    with pytest.raises(ParamError, match="unknown parameter"):
        parameter_values(vehicle, {"ATT_MAG_DECL": 3.2})
