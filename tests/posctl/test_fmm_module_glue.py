"""The flight_mode_manager module on a bench: what it hands the flight mode manager from the bus and what it
publishes from its answer (PX4 src/modules/flight_mode_manager/FlightModeManager.cpp)."""

import math

import pytest

from stack.commander.home import HomePosition
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import TakeoffStatus
from stack.msg.system import HomePosition as HomePositionMsg
from stack.msg.system import VehicleLandDetected, VehicleStatus
from stack.posctl.flight_mode_manager import FlightModeManager
from stack.posctl.flight_task import TrajectoryCommand
from stack.posctl.fmm_module import FlightModeManagerModule
from tests.support.bench import ModuleBench, stand_in

DT = 0.02
LPOS = VehicleLocalPosition(timestamp_sample=555, xy_valid=True, z_valid=False, v_xy_valid=False, v_z_valid=True,
                            x=1.0, y=2.0, z=-3.0, vx=0.5, vy=0.6, vz=-0.7, heading=0.3)


@pytest.fixture
def answers(monkeypatch):
    """What the manager was asked (inputs, dt); it answers ``answers.returns``."""
    return stand_in(monkeypatch, FlightModeManager, "update")


def test_reads_and_writes_the_topics_of_px4s_modules():
    bench = ModuleBench(FlightModeManagerModule)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_status, ORB_ID.navigation_request, ORB_ID.home_position, ORB_ID.takeoff_status,
                  ORB_ID.vehicle_land_detected, ORB_ID.manual_control_setpoint, ORB_ID.mission)
    }
    assert set(bench.outputs) == {(ORB_ID.trajectory_setpoint.name, 0), (ORB_ID.mission_result.name, 0)}


def test_with_nothing_known_the_vehicle_reads_landed_disarmed_without_home_or_mode(answers):
    bench = ModuleBench(FlightModeManagerModule)
    bench.run(LPOS, DT)
    inputs, dt = answers[-1]
    assert dt == DT
    state = inputs.state
    assert state.now_us == 555 and state.yaw == 0.3
    assert state.position[:2] == (1.0, 2.0) and math.isnan(state.position[2])  # z not valid
    assert math.isnan(state.velocity[0]) and math.isnan(state.velocity[1]) and state.velocity[2] == -0.7
    assert state.landed and not state.flying
    assert (inputs.nav_state, inputs.armed, inputs.home, inputs.request, inputs.manual) == (-1, False, None, None, None)
    assert bench.sent(ORB_ID.trajectory_setpoint) == []  # no command: nothing published


def test_mode_arming_takeoff_stage_and_a_valid_home_reach_the_manager(answers):
    bench = ModuleBench(FlightModeManagerModule)
    bench.put(ORB_ID.vehicle_status, VehicleStatus(nav_state=VehicleStatus.NAVIGATION_STATE_AUTO_LOITER,
                                                   arming_state=VehicleStatus.ARMING_STATE_ARMED))
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False))
    bench.put(ORB_ID.takeoff_status, TakeoffStatus(takeoff_state=TakeoffStatus.TAKEOFF_STATE_FLIGHT))
    bench.put(ORB_ID.home_position, HomePositionMsg(x=1.0, y=2.0, z=0.5, yaw=0.1, valid_lpos=False))
    bench.run(LPOS, DT)
    inputs = answers[-1][0]
    assert inputs.nav_state == VehicleStatus.NAVIGATION_STATE_AUTO_LOITER and inputs.armed
    assert not inputs.state.landed and inputs.state.flying
    assert inputs.home is None  # not valid in the local frame
    bench.put(ORB_ID.home_position, HomePositionMsg(x=1.0, y=2.0, z=0.5, yaw=0.1, valid_lpos=True))
    bench.run(LPOS, DT)
    home = answers[-1][0].home
    assert home[:4] == HomePosition(1.0, 2.0, 0.5, 0.1)[:4]


def test_the_managers_command_is_published_as_the_trajectory_setpoint_stamped_now(answers):
    bench = ModuleBench(FlightModeManagerModule)
    answers.returns = TrajectoryCommand(position=(1.0, 2.0, -3.0), yaw=0.5, yawspeed=0.1)
    bench.run(LPOS, DT)
    sp = bench.sent(ORB_ID.trajectory_setpoint)[-1]
    assert sp.timestamp == bench.now
    assert (sp.position, sp.yaw, sp.yawspeed) == ((1.0, 2.0, -3.0), 0.5, 0.1)
    assert all(math.isnan(v) for v in sp.velocity)


def test_a_parameter_change_reaches_the_manager():
    bench = ModuleBench(FlightModeManagerModule, {"MPC_XY_CRUISE": 5.0})
    assert bench.module.manager._p.smoothing.mpc_xy_cruise == 5.0
    bench.set_param("MPC_XY_CRUISE", 7.5)
    assert bench.module.manager._p.smoothing.mpc_xy_cruise == 7.5
