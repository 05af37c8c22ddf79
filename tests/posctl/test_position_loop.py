"""PositionLoop, mc_pos_control's cycle without I/O (PX4 MulticopterPositionControl::Run): when it controls, the
setpoint it flies, the failsafe setpoint, ground contact and a kept integral."""

import math

from stack.msg.estimation import VehicleLocalPosition
from stack.msg.setpoints import TakeoffState, TrajectorySetpoint
from stack.msg.system import VehicleLandDetected
from stack.posctl.position_control import PositionControlParams
from stack.posctl.position_loop import SETPOINT_TIMEOUT_US, SETPOINT_WAIT_US, PositionLoop
from stack.posctl.takeoff import TakeoffParams

DT = 0.02
IN_AIR = VehicleLandDetected(landed=False, maybe_landed=False, ground_contact=False)
LPOS = VehicleLocalPosition(xy_valid=True, z_valid=True, v_xy_valid=True, v_z_valid=True, z=-5.0)


def loop(kept_integral=None) -> PositionLoop:
    return PositionLoop(PositionControlParams(), TakeoffParams(), use_hover_thrust_estimate=True, land_speed=0.7,
                        velocity_derivative_cutoff=5.0, kept_integral=kept_integral)


def cycle(lp: PositionLoop, now: int, land=IN_AIR, setpoint=None, enabled=True, lpos=LPOS):
    return lp.update(now, DT, lpos, enabled=enabled, armed=True, land=land, setpoint=setpoint,
                     hover_thrust_estimate=None)


def test_nothing_without_position_control_or_a_land_detector_and_the_takeoff_skipped_outside_it():
    lp = loop()
    assert cycle(lp, 20_000, enabled=False).setpoints is False
    assert lp.takeoff.state == TakeoffState.FLIGHT
    assert cycle(loop(), 20_000, land=None).setpoints is False


def test_a_missing_setpoint_is_waited_for_then_replaced_by_the_failsafe_setpoint():
    lp = loop()
    assert cycle(lp, 20_000).setpoints is False
    assert cycle(lp, 20_000 + SETPOINT_WAIT_US).setpoints is True
    assert lp.failsafe_action != ""


def test_a_fresh_setpoint_is_flown_and_a_stale_one_is_not():
    lp = loop()
    sp = TrajectorySetpoint(timestamp=20_000, position=(0.0, 0.0, -6.0), yaw=0.0)
    assert cycle(lp, 20_000, setpoint=sp).setpoints is True
    assert lp.failsafe_action == "" and lp.control.local_position_setpoint().position[2] == -6.0
    cycle(lp, 20_001 + SETPOINT_TIMEOUT_US, setpoint=sp)
    assert lp.failsafe_action != ""


def test_ground_contact_in_flight_pushes_down_and_resets_the_integral():
    lp = loop(kept_integral=[0.0, 0.0, 0.3])
    sp = TrajectorySetpoint(timestamp=20_000, position=(0.0, 0.0, -5.0))
    result = cycle(lp, 20_000, setpoint=sp)
    assert result.resumed_integral is True
    cycle(lp, 40_000, land=VehicleLandDetected(landed=False, ground_contact=True), setpoint=sp)
    assert lp.control.velocity_integral == (0.0, 0.0, 0.0)
    assert math.isnan(lp.control.local_position_setpoint().position[2])
    assert lp.control.thrust_setpoint[2] > -0.5  # less than hover: pushed down
