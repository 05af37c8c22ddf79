"""The mc_pos_control module on a bench: when it controls, the setpoint it executes or replaces by the failsafe
setpoint, the hover thrust it adopts, what it publishes
(PX4 src/modules/mc_pos_control/MulticopterPositionControl.cpp)."""

import math

import pytest

from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import HoverThrustEstimate, TakeoffStatus, TrajectorySetpoint
from stack.msg.system import VehicleControlMode, VehicleLandDetected
from stack.posctl.pos_module import MulticopterPositionControl
from stack.posctl.position_loop import SETPOINT_TIMEOUT_US, SETPOINT_WAIT_US
from tests.support.bench import ModuleBench

DT = 0.02
POSITION = VehicleControlMode(flag_armed=True, flag_multicopter_position_control_enabled=True,
                              flag_control_position_enabled=True)
IN_AIR = VehicleLandDetected(landed=False, maybe_landed=False, ground_contact=False)


def step(bench: ModuleBench, z=-5.0, valid=True) -> None:
    bench.run(VehicleLocalPosition(timestamp_sample=bench.now + 1000, xy_valid=valid, z_valid=valid,
                                   v_xy_valid=valid, v_z_valid=valid, z=z), DT)


def flying(**params) -> ModuleBench:
    bench = ModuleBench(MulticopterPositionControl, {"MPC_THR_HOVER": 0.5, **params})
    bench.put(ORB_ID.vehicle_control_mode, POSITION)
    bench.put(ORB_ID.vehicle_land_detected, IN_AIR)
    return bench


def hold(bench: ModuleBench, z=-5.0) -> None:
    """A setpoint to hold (0, 0, z), stamped at the next run (one from before position control was enabled is
    not executed)."""
    bench.put(ORB_ID.trajectory_setpoint,
              TrajectorySetpoint(timestamp=bench.now + round(DT * 1e6), position=(0.0, 0.0, z), yaw=0.0))


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(MulticopterPositionControl)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.trajectory_setpoint, ORB_ID.vehicle_control_mode, ORB_ID.vehicle_land_detected,
                  ORB_ID.hover_thrust_estimate)
    }
    assert set(bench.outputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_attitude_setpoint, ORB_ID.vehicle_local_position_setpoint, ORB_ID.takeoff_status)
    }


def test_outside_position_control_only_the_takeoff_stage_is_published_once_a_second():
    bench = ModuleBench(MulticopterPositionControl)
    bench.put(ORB_ID.vehicle_control_mode, VehicleControlMode(flag_armed=True))
    for _ in range(60):  # 1.2 s
        step(bench)
    assert bench.sent(ORB_ID.vehicle_attitude_setpoint) == []
    statuses = bench.sent(ORB_ID.takeoff_status)
    assert len(statuses) == 2 and statuses[0].timestamp == DT * 1e6
    assert statuses[-1].takeoff_state == TakeoffStatus.TAKEOFF_STATE_FLIGHT  # takeoff skipped, as in PX4


def test_waits_for_the_land_detector_then_for_a_setpoint():
    bench = ModuleBench(MulticopterPositionControl)
    bench.put(ORB_ID.vehicle_control_mode, POSITION)
    step(bench)
    assert bench.sent(ORB_ID.takeoff_status) == []  # no land detector: nothing known, nothing done
    bench.put(ORB_ID.vehicle_land_detected, IN_AIR)
    waited = 0
    while not bench.sent(ORB_ID.vehicle_attitude_setpoint):
        step(bench)
        waited += 1
    assert waited * DT * 1e6 >= SETPOINT_WAIT_US


def test_executes_the_trajectory_setpoint_and_publishes_both_setpoints_stamped_now():
    bench = flying()
    hold(bench, z=-6.0)  # a metre below the setpoint: more thrust than hover
    step(bench)
    att = bench.sent(ORB_ID.vehicle_attitude_setpoint)[-1]
    local = bench.sent(ORB_ID.vehicle_local_position_setpoint)[-1]
    assert att.timestamp == local.timestamp == bench.now
    assert local.z == -6.0 and local.thrust[2] < -0.5 and att.thrust_body[2] == pytest.approx(local.thrust[2])
    assert quat.to_euler(att.q_d)[:2] == pytest.approx((0.0, 0.0))
    assert bench.module._failsafe_action == ""


def test_a_stale_setpoint_or_an_invalid_estimate_flies_the_failsafe_setpoint():
    bench = flying()
    hold(bench)
    step(bench)
    bench.now += SETPOINT_TIMEOUT_US
    step(bench)
    assert bench.module._failsafe_action != ""
    blind = flying()
    hold(blind)
    step(blind, valid=False)
    assert blind.module._failsafe_action != ""
    assert all(math.isfinite(v) for v in blind.sent(ORB_ID.vehicle_attitude_setpoint)[-1].thrust_body)


def test_the_hover_thrust_estimate_is_adopted_in_flight_when_enabled():
    estimate = HoverThrustEstimate(hover_thrust=0.6, valid=True)
    bench = flying(MPC_USE_HTE=True)
    bench.put(ORB_ID.hover_thrust_estimate, estimate)
    hold(bench)
    step(bench)
    assert bench.module.control.hover_thrust == pytest.approx(0.6)
    ignored = flying(MPC_USE_HTE=False)
    ignored.put(ORB_ID.hover_thrust_estimate, estimate)
    hold(ignored)
    step(ignored)
    assert ignored.module.control.hover_thrust == pytest.approx(0.5)


def test_a_gain_change_reaches_the_controller():
    bench = flying(MPC_Z_P=1.0)
    hold(bench, z=-6.0)
    step(bench)
    before = bench.sent(ORB_ID.vehicle_local_position_setpoint)[-1].vz
    bench.set_param("MPC_Z_P", 0.5)
    hold(bench, z=-6.0)
    step(bench)
    assert bench.sent(ORB_ID.vehicle_local_position_setpoint)[-1].vz == pytest.approx(before / 2)
