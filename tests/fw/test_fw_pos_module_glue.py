"""The fw_pos_control module on a bench: what it needs before it runs, what it hands the position controller from
the bus (fresh airspeed and wind only) and what it publishes from its answer
(PX4 src/modules/fw_pos_control_l1/FixedwingPositionControl.cpp)."""

import math

import pytest

from stack.fw.pos_control import FixedwingPositionControl as PositionController
from stack.fw.pos_control import FwPosOutput
from stack.fw.pos_module import FixedwingPositionControl
from stack.mathlib import quaternion as quat
from stack.msg.estimation import VehicleAttitude, VehicleLocalPosition
from stack.msg.fixedwing import AirspeedValidated, Wind
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleLandDetected, VehicleStatus
from tests.support.bench import ModuleBench, stand_in

DT = 0.02
LPOS = VehicleLocalPosition(timestamp_sample=321, xy_valid=True, z_valid=True, v_xy_valid=True, v_z_valid=False,
                            x=10.0, y=20.0, z=-30.0, vx=15.0, vy=1.0, vz=-2.0, az=0.5)
ARMED_MISSION = VehicleStatus(nav_state=VehicleStatus.NAVIGATION_STATE_AUTO_MISSION,
                              arming_state=VehicleStatus.ARMING_STATE_ARMED)
OUT = FwPosOutput(roll=0.2, pitch=0.1, yaw=1.0, throttle=0.7, wheel_steering=True, reset_integral=True)


@pytest.fixture
def asked(monkeypatch):
    return stand_in(monkeypatch, PositionController, "update")


def ready() -> ModuleBench:
    bench = ModuleBench(FixedwingPositionControl)
    bench.put(ORB_ID.vehicle_status, ARMED_MISSION)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude(q=quat.from_euler(0.1, 0.05, 0.3)))
    return bench


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(FixedwingPositionControl)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_status, ORB_ID.vehicle_attitude, ORB_ID.airspeed_validated, ORB_ID.wind,
                  ORB_ID.position_setpoint_triplet, ORB_ID.manual_control_setpoint, ORB_ID.vehicle_land_detected)
    }
    assert set(bench.outputs) == {
        (t.name, 0)
        for t in (ORB_ID.vehicle_attitude_setpoint, ORB_ID.tecs_status, ORB_ID.position_controller_status)
    }


def test_waits_for_a_status_and_a_finite_attitude(asked):
    bench = ModuleBench(FixedwingPositionControl)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude())
    bench.run(LPOS, DT)
    bench.put(ORB_ID.vehicle_status, ARMED_MISSION)
    bench.put(ORB_ID.vehicle_attitude, VehicleAttitude(q=(math.nan, 0.0, 0.0, 0.0)))
    bench.run(LPOS, DT)
    assert asked == []


def test_the_estimate_mode_and_attitude_reach_the_controller(asked):
    bench = ready()
    bench.run(LPOS, DT)
    (inputs,) = asked[-1]
    assert (inputs.now_us, inputs.dt, inputs.nav_state, inputs.armed, inputs.landed) == (
        321, DT, VehicleStatus.NAVIGATION_STATE_AUTO_MISSION, True, True)  # no land detector: landed
    assert inputs.position == (10.0, 20.0, -30.0) and inputs.velocity[:2] == (15.0, 1.0)
    assert math.isnan(inputs.velocity[2]) and inputs.acceleration == (0.0, 0.0, 0.5)
    assert (inputs.roll, inputs.pitch, inputs.yaw) == pytest.approx((0.1, 0.05, 0.3))
    assert math.isnan(inputs.airspeed) and inputs.eas_to_tas == 1.0 and all(math.isnan(w) for w in inputs.wind)
    bench.put(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False))
    bench.run(LPOS, DT)
    assert not asked[-1][0].landed


def test_airspeed_and_wind_count_only_while_fresh(asked):
    bench = ready()
    bench.put(ORB_ID.airspeed_validated, AirspeedValidated(calibrated_airspeed_m_s=15.0, true_airspeed_m_s=16.5))
    bench.put(ORB_ID.wind, Wind(windspeed_north=3.0, windspeed_east=-1.0))
    bench.run(LPOS, DT)
    (inputs,) = asked[-1]
    assert (inputs.airspeed, inputs.eas_to_tas, inputs.wind) == (15.0, pytest.approx(1.1), (3.0, -1.0))
    bench.now += 1_000_000
    bench.run(LPOS, DT)
    (inputs,) = asked[-1]
    assert math.isnan(inputs.airspeed) and math.isnan(inputs.wind[0])


def test_the_answer_is_published_as_the_attitude_setpoint_stamped_now(asked):
    bench = ready()
    bench.run(LPOS, DT)
    assert bench.sent(ORB_ID.vehicle_attitude_setpoint) == []  # no answer: nothing published
    asked.returns = OUT
    bench.run(LPOS, DT)
    sp = bench.sent(ORB_ID.vehicle_attitude_setpoint)[-1]
    assert sp.timestamp == bench.now
    assert quat.to_euler(sp.q_d) == pytest.approx((0.2, 0.1, 1.0))
    assert sp.thrust_body == (0.7, 0.0, 0.0) and sp.fw_control_yaw_wheel and sp.reset_integral
    assert bench.sent(ORB_ID.tecs_status)[-1].timestamp == bench.now
    assert bench.sent(ORB_ID.position_controller_status)[-1].timestamp == bench.now


def test_a_parameter_change_reaches_the_controller(monkeypatch):
    bench = ModuleBench(FixedwingPositionControl)
    seen = stand_in(monkeypatch, PositionController, "set_params")
    bench.set_param("FW_AIRSPD_TRIM", 17.0)
    assert seen[-1][0]["FW_AIRSPD_TRIM"] == 17.0
