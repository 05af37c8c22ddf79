"""fw_pos_control's modes worked by hand: which guidance flies, the runway takeoff, the roll-out, the pilot's modes."""

from __future__ import annotations

import itertools
import math

import msgspec
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


def fly_flare(control: FixedwingPositionControl, seconds: float, **state) -> list:
    """An approach step at 5 m, then ``seconds`` of steps at 0.5 m (the flare), all in ``state``; the outputs."""
    land = line(SP.SETPOINT_TYPE_LAND, start=(-300.0, 0.0, -15.0), end=(0.0, 0.0, 0.0))
    rtl = NS.NAVIGATION_STATE_AUTO_RTL
    outs = [control.update(inputs(rtl, land, now_us=0, position=(-60.0, 0.0, -5.0), **state))]
    for i in range(round(seconds / 0.004)):
        outs.append(control.update(inputs(rtl, land, now_us=4000 * (i + 1), position=(-50.0, 0.0, -0.5), **state)))
    return outs


def test_the_flare_flies_a_height_rate_and_takes_the_throttle_to_idle() -> None:
    control = FixedwingPositionControl({"FW_THR_IDLE": 0.05})
    outs = fly_flare(control, 1.5, velocity=(13.0, 0.0, 1.0), airspeed=13.0)
    assert control.landing.flaring and not outs[-1].wheel_steering
    # From the sink rate at its start to FW_LND_FL_SINK in FW_LND_FL_TIME, with no altitude to track.
    assert control.landing.flare_initial_height_rate == -1.0
    status = control.tecs.status()
    assert math.isnan(status.altitude_sp) and status.height_rate_setpoint == pytest.approx(-0.25)
    # The throttle leaves the approach's smoothly and ends at idle.
    steps = [abs(b.throttle - a.throttle) for a, b in itertools.pairwise(outs)]
    assert max(steps) < 0.05
    assert outs[-1].throttle == pytest.approx(0.05)


def test_in_the_flare_the_pitch_gives_way_to_the_airspeed_before_the_wing_stalls() -> None:
    # Half way through the flare's ramp, sinking at 1 m/s: far below the minimum airspeed TECS' underspeed protection
    # flies the airspeed (towards FW_AIRSPD_MIN) instead of the sink rate, nose down.
    pitch = {}
    for airspeed in (13.0, 5.0):
        control = FixedwingPositionControl({"FW_LND_FL_PMIN": 0.0})
        outs = fly_flare(control, 0.5, velocity=(airspeed, 0.0, 1.0), airspeed=airspeed)
        pitch[airspeed] = outs[-1].pitch
        status = control.tecs.status()
        assert status.underspeed_ratio == (1.0 if airspeed < 10.0 else 0.0)
        assert status.true_airspeed_sp == (10.0 if airspeed < 10.0 else 13.0)
    assert pitch[5.0] < pitch[13.0] - math.radians(4.0)


def test_just_above_the_runway_it_steers_on_the_wheels_at_idle_but_keeps_the_flares_pitch() -> None:
    control = FixedwingPositionControl({"FW_LND_FL_PMIN": 0.0, "FW_THR_IDLE": 0.05})
    fly_flare(control, 0.3, velocity=(12.0, 0.0, 1.0), airspeed=12.0)
    land = line(SP.SETPOINT_TYPE_LAND, start=(-300.0, 0.0, -15.0), end=(0.0, 0.0, 0.0))
    low = dict(now_us=304_000, position=(-49.0, 0.0, -0.2), velocity=(12.0, 0.0, 1.0), airspeed=12.0)
    out = control.update(inputs(NS.NAVIGATION_STATE_AUTO_RTL, land, **low))
    assert out.wheel_steering and out.reset_integral and out.roll == 0.0 and out.throttle == 0.05
    # Nose below the flare's final least pitch: not raised to it while the vehicle may still be floating.
    assert out.pitch == control.tecs.status().pitch_sp_rad < 0.0


def test_altitude_mode_banks_with_the_stick_and_descend_circles_gently() -> None:
    control = FixedwingPositionControl({"FW_MAN_R_MAX": 45.0})
    sticks = ManualControlSetpoint(valid=True, roll=0.5, pitch=0.0, throttle=0.0)
    out = control.update(inputs(NS.NAVIGATION_STATE_ALTCTL, manual=sticks))
    assert out.roll == pytest.approx(math.radians(22.5))
    out = control.update(inputs(NS.NAVIGATION_STATE_DESCEND, position=(math.nan, math.nan, -40.0)))
    assert out.roll == DESCEND_BANK


def test_the_least_airspeed_rises_with_the_load_factor_of_the_bank() -> None:
    # PX4 v1.14 adapt_airspeed_setpoint: the stall speed, and so FW_AIRSPD_MIN, grows as √(1/cos(roll)).
    control = FixedwingPositionControl({"FW_AIRSPD_MIN": 10.0, "FW_AIRSPD_TRIM": 15.0, "FW_AIRSPD_MAX": 20.0})
    triplet = line()
    triplet = msgspec.structs.replace(triplet, current=msgspec.structs.replace(triplet.current, cruising_speed=10.0))
    far_right = inputs(NS.NAVIGATION_STATE_AUTO_MISSION, triplet, position=(0.0, 300.0, -40.0))
    banks = [control.update(far_right).roll for _ in range(500)]  # the roll setpoint slews at FW_L1_R_SLEW_MAX
    assert banks[-1] < -math.radians(20.0)
    assert control.tecs.status().true_airspeed_sp == pytest.approx(10.0 / math.sqrt(math.cos(banks[-2])))
    on_the_line = inputs(NS.NAVIGATION_STATE_AUTO_MISSION, triplet)
    for _ in range(500):
        control.update(on_the_line)
    assert control.tecs.status().true_airspeed_sp == pytest.approx(10.0)
