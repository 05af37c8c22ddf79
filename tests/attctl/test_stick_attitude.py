"""Stabilized mode's setpoint as the attitude loops make it each cycle: its thrust limits slew in every mode, so a
switch to Stabilized in flight has the full thrust range at once."""

import pytest

from stack.attctl.stick_attitude import StickAttitudeSetpoint, stabilized_mode
from stack.commander.modes import control_mode
from stack.mathlib import quaternion as quat
from stack.msg.setpoints import ManualControlSetpoint
from stack.msg.system import VehicleStatus as NS

DT = 0.004
CENTRED = ManualControlSetpoint(valid=True, throttle=0.0)
HOVER = 0.5  # MPC_THR_HOVER's default


def _fly(sticks: StickAttitudeSetpoint, nav_state: int, seconds: float, t_us: int, landed: bool = False) -> int:
    mode = control_mode(nav_state, True)
    for _ in range(round(seconds / DT)):
        t_us += round(DT * 1e6)
        sticks.update(quat.IDENTITY, mode, CENTRED, landed, DT, t_us)
    return t_us


def test_only_the_stick_attitude_modes_make_a_setpoint():
    states = (NS.NAVIGATION_STATE_STAB, NS.NAVIGATION_STATE_MANUAL, NS.NAVIGATION_STATE_POSCTL,
              NS.NAVIGATION_STATE_ACRO, NS.NAVIGATION_STATE_EXTERNAL1)
    stabilized = [s for s in states if stabilized_mode(control_mode(s, True))]
    assert stabilized == [NS.NAVIGATION_STATE_STAB, NS.NAVIGATION_STATE_MANUAL]
    assert StickAttitudeSetpoint().update(quat.IDENTITY, control_mode(NS.NAVIGATION_STATE_POSCTL, True), CENTRED,
                                          False, DT, 0) is None


def test_entering_stabilized_in_flight_gives_hover_thrust_at_the_centred_stick_at_once():
    sticks = StickAttitudeSetpoint()
    t = _fly(sticks, NS.NAVIGATION_STATE_AUTO_LOITER, 10.0, 0)
    sp = sticks.update(quat.IDENTITY, control_mode(NS.NAVIGATION_STATE_STAB, True), CENTRED, False, DT, t)
    assert sp is not None and sp.thrust_body == pytest.approx((0.0, 0.0, -HOVER))


def test_just_armed_the_thrust_waits_for_the_spool_up_time():
    sticks = StickAttitudeSetpoint({"COM_SPOOLUP_TIME": 1.0})
    t = _fly(sticks, NS.NAVIGATION_STATE_STAB, 0.5, 0, landed=True)
    stab = control_mode(NS.NAVIGATION_STATE_STAB, True)
    assert sticks.update(quat.IDENTITY, stab, CENTRED, True, DT, t).thrust_body[2] == 0.0
    t = _fly(sticks, NS.NAVIGATION_STATE_STAB, 2.0, t, landed=True)
    assert sticks.update(quat.IDENTITY, stab, CENTRED, True, DT, t).thrust_body[2] == pytest.approx(-HOVER)
