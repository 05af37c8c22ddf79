"""The navigator module on a bench: what it hands the fixed-wing navigator from the bus and what it publishes from
its answer (PX4 src/modules/navigator/navigator_main.cpp)."""

import math

import pytest

from stack.fw.navigator import FixedwingNavigator
from stack.fw.navigator_module import NavigatorModule
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.fixedwing import PositionControllerStatus, PositionSetpoint, PositionSetpointTriplet
from stack.msg.registry import ORB_ID
from stack.msg.system import HomePosition, VehicleLandDetected, VehicleStatus
from tests.support.bench import ModuleBench, stand_in

DT = 0.02
LPOS = VehicleLocalPosition(timestamp_sample=654, xy_valid=False, z_valid=True, x=1.0, y=2.0, z=-40.0, heading=0.4)


@pytest.fixture
def asked(monkeypatch):
    return stand_in(monkeypatch, FixedwingNavigator, "update")


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(NavigatorModule)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_status, ORB_ID.navigation_request, ORB_ID.home_position,
                  ORB_ID.vehicle_land_detected, ORB_ID.position_controller_status, ORB_ID.mission)
    }
    assert set(bench.outputs) == {(ORB_ID.position_setpoint_triplet.name, 0), (ORB_ID.mission_result.name, 0)}


def test_with_nothing_known_the_vehicle_reads_landed_disarmed_without_home(asked):
    bench = ModuleBench(NavigatorModule)
    bench.run(LPOS, DT)
    (inputs,) = asked[-1]
    assert (inputs.now_us, inputs.nav_state, inputs.armed, inputs.landed, inputs.home, inputs.request) == (
        654, -1, False, True, None, None)
    assert math.isnan(inputs.position[0]) and math.isnan(inputs.position[1]) and inputs.position[2] == -40.0
    assert inputs.yaw == 0.4 and math.isnan(inputs.acceptance_radius)
    assert bench.sent(ORB_ID.position_setpoint_triplet) == []


def test_mode_arming_land_home_and_the_guidances_radius_reach_the_navigator(asked):
    bench = ModuleBench(NavigatorModule)
    bench.put(ORB_ID.vehicle_status, VehicleStatus(nav_state=VehicleStatus.NAVIGATION_STATE_AUTO_MISSION,
                                                   arming_state=VehicleStatus.ARMING_STATE_ARMED))
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False))
    bench.put(ORB_ID.home_position, HomePosition(x=5.0, y=6.0, z=0.0, yaw=0.2, valid_lpos=True))
    bench.put(ORB_ID.position_controller_status, PositionControllerStatus(acceptance_radius=25.0))
    bench.run(LPOS, DT)
    (inputs,) = asked[-1]
    assert inputs.nav_state == VehicleStatus.NAVIGATION_STATE_AUTO_MISSION and inputs.armed and not inputs.landed
    assert inputs.home[:4] == (5.0, 6.0, 0.0, 0.2) and inputs.acceptance_radius == 25.0


def test_the_triplet_is_published_stamped_now(asked):
    bench = ModuleBench(NavigatorModule)
    asked.returns = PositionSetpointTriplet(current=PositionSetpoint(valid=True, x=100.0, y=0.0, z=-50.0))
    bench.run(LPOS, DT)
    triplet = bench.sent(ORB_ID.position_setpoint_triplet)[-1]
    assert triplet.timestamp == bench.now and triplet.current.x == 100.0


def test_a_parameter_change_reaches_the_navigator(monkeypatch):
    bench = ModuleBench(NavigatorModule)
    seen = stand_in(monkeypatch, FixedwingNavigator, "set_params")
    name = "NAV_ACC_RAD"
    bench.set_param(name, 12.0)
    assert seen[-1][0][name] == 12.0
