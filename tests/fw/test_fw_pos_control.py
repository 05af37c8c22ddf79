"""fw_pos_control's modes worked by hand: which guidance flies, the runway takeoff, the roll-out, the pilot's modes."""

from __future__ import annotations

import math

import pytest

from stack.fw.pos_control import DESCEND_BANK, FixedwingPositionControl, FwPosInputs
from stack.msg.fixedwing import PositionSetpoint, PositionSetpointTriplet
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus

NS = VehicleStatus
SP = PositionSetpoint


def inputs(nav: int, triplet=None, **kw) -> FwPosInputs:
    base = dict(now_us=10_000_000, dt=0.004, nav_state=nav, armed=True, landed=False, position=(0.0, 0.0, -40.0),
                velocity=(15.0, 0.0, 0.0), acceleration=(0.0, 0.0, 0.0), roll=0.0, pitch=0.0, yaw=0.0,
                airspeed=15.0, eas_to_tas=1.0, wind=(math.nan, math.nan), triplet=triplet, manual=None)
    base.update(kw)
    return FwPosInputs(**base)


def line(kind: int = SP.SETPOINT_TYPE_POSITION, start=(-100.0, 0.0, -40.0), end=(400.0, 0.0, -40.0)):
    return PositionSetpointTriplet(
        previous=PositionSetpoint(valid=True, type=SP.SETPOINT_TYPE_POSITION, x=start[0], y=start[1], z=start[2]),
        current=PositionSetpoint(valid=True, type=kind, x=end[0], y=end[1], z=end[2]),
    )


@pytest.mark.parametrize("use_npfg", [0, 1])
def test_on_the_line_at_its_altitude_and_speed_it_flies_wings_level(use_npfg: int) -> None:
    control = FixedwingPositionControl({"FW_USE_NPFG": use_npfg})
    assert control.guidance is (control.npfg if use_npfg else control.l1)
    out = control.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, line()))
    assert out.roll == pytest.approx(0.0, abs=1e-6) and out.yaw == pytest.approx(0.0)
    assert not out.wheel_steering and 0.0 <= out.throttle <= 1.0
    assert control.status.xtrack_error == pytest.approx(0.0, abs=1e-9) and control.status.wp_dist == 400.0


@pytest.mark.parametrize("use_npfg", [0, 1])
def test_right_of_the_line_it_banks_left_toward_it(use_npfg: int) -> None:
    control = FixedwingPositionControl({"FW_USE_NPFG": use_npfg})
    out = control.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, line(), position=(0.0, 20.0, -40.0)))
    assert -math.radians(50.0) <= out.roll < 0.0


def test_disarmed_or_in_a_manual_mode_it_commands_nothing() -> None:
    control = FixedwingPositionControl()
    assert control.update(inputs(NS.NAVIGATION_STATE_AUTO_MISSION, line(), armed=False)) is None
    assert control.update(inputs(NS.NAVIGATION_STATE_STAB)) is None
    assert control.update(inputs(NS.NAVIGATION_STATE_MANUAL)) is None


def test_the_runway_takeoff_ramps_the_throttle_with_the_heading_held_on_the_wheels() -> None:
    control = FixedwingPositionControl({"RWTO_RAMP_TIME": 2.0, "RWTO_MAX_THR": 1.0})
    takeoff = line(SP.SETPOINT_TYPE_TAKEOFF, start=(0.0, 0.0, 0.0), end=(2000.0, 0.0, -30.0))
    at_rest = dict(position=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0), airspeed=0.0, landed=True, yaw=0.1)
    first = control.update(inputs(NS.NAVIGATION_STATE_AUTO_TAKEOFF, takeoff, now_us=0, **at_rest))
    half = control.update(inputs(NS.NAVIGATION_STATE_AUTO_TAKEOFF, takeoff, now_us=1_000_000, **at_rest))
    assert first.throttle == pytest.approx(0.0) and half.throttle == pytest.approx(0.5)
    assert half.wheel_steering and half.reset_integral and half.roll == 0.0 and half.yaw == 0.1
    assert half.pitch == pytest.approx(0.0)  # RWTO_PSP


def test_after_the_flare_it_rolls_out_at_idle_steering_along_the_runway() -> None:
    control = FixedwingPositionControl({"FW_THR_IDLE": 0.0})
    land = line(SP.SETPOINT_TYPE_LAND, start=(-300.0, 0.0, -15.0), end=(0.0, 0.0, 0.0))
    out = control.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, land, position=(5.0, 0.5, -0.1),
                                velocity=(10.0, 0.0, 0.0), landed=True))
    assert out.wheel_steering and out.throttle == 0.0 and out.roll == 0.0 and out.yaw == pytest.approx(0.0)


@pytest.mark.parametrize("limit", [0.0, 0.3])
def test_below_the_throttle_limit_altitude_the_flare_keeps_at_most_fw_thr_lnd_max(limit: float) -> None:
    control = FixedwingPositionControl({"FW_THR_LND_MAX": limit, "FW_LND_FLALT": 3.0, "FW_LND_TLALT": -1.0})
    land = line(SP.SETPOINT_TYPE_LAND, start=(-300.0, 0.0, -15.0), end=(0.0, 0.0, 0.0))
    slow = dict(velocity=(8.0, 0.0, 0.5), airspeed=8.0)  # well below the landing airspeed: TECS asks for throttle
    flaring = control.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, land, position=(-30.0, 0.0, -2.5), **slow))
    assert flaring.throttle > 0.3  # above FW_LND_TLALT (2/3 of the flare altitude) the throttle is TECS'
    limited = control.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, land, position=(-20.0, 0.0, -1.5), **slow))
    assert 0.0 <= limited.throttle <= limit and not limited.wheel_steering


def test_altitude_mode_banks_with_the_stick_and_descend_circles_gently() -> None:
    control = FixedwingPositionControl({"FW_MAN_R_MAX": 45.0})
    sticks = ManualControlSetpoint(valid=True, roll=0.5, pitch=0.0, throttle=0.0)
    out = control.update(inputs(NS.NAVIGATION_STATE_ALTCTL, manual=sticks))
    assert out.roll == pytest.approx(math.radians(22.5))
    out = control.update(inputs(NS.NAVIGATION_STATE_DESCEND, position=(math.nan, math.nan, -40.0)))
    assert out.roll == DESCEND_BANK
