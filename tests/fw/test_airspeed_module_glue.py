"""The airspeed_selector module on a bench: when it counts the vehicle in fixed-wing flight, which velocity it gives
the wind estimator, and what it publishes (PX4 src/modules/airspeed_selector/airspeed_selector_main.cpp)."""

import math

import pytest

from stack.fw.airspeed_module import AirspeedSelectorModule
from stack.fw.airspeed_validator import AirspeedValidator
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.fixedwing import Airspeed, PositionSetpoint, PositionSetpointTriplet
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleLandDetected
from tests.support.bench import ModuleBench

DT = 0.1
IN_AIR = VehicleLandDetected(landed=False)


@pytest.fixture
def fed(monkeypatch):
    """Each ``AirspeedValidator.update`` call's keyword arguments."""
    calls = []
    original = AirspeedValidator.update

    def update(self, *args, **kwargs):
        calls.append(kwargs)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(AirspeedValidator, "update", update)
    return calls


def step(bench: ModuleBench, ias=None) -> None:
    if ias is not None:
        bench.put(ORB_ID.airspeed, Airspeed(indicated_airspeed_m_s=ias, true_airspeed_m_s=ias))
    bench.run(None, DT)


def test_reads_and_writes_the_topics_of_px4s_module():
    bench = ModuleBench(AirspeedSelectorModule)
    assert set(bench.inputs) == {
        (t.name, 0)
        for t in (ORB_ID.airspeed, ORB_ID.vehicle_local_position, ORB_ID.vehicle_attitude,
                  ORB_ID.vehicle_land_detected, ORB_ID.position_setpoint_triplet)
    }
    assert set(bench.outputs) == {(ORB_ID.airspeed_validated.name, 0), (ORB_ID.wind.name, 0)}


def test_fixed_wing_flight_only_in_the_air_past_the_takeoff_run_and_not_landing(fed):
    bench = ModuleBench(AirspeedSelectorModule, {"FW_AIRSPD_STALL": 7.0})
    step(bench, ias=15.0)  # no land detector: not in the air
    bench.put(ORB_ID.vehicle_land_detected, IN_AIR)
    step(bench, ias=5.0)  # in the takeoff run
    step(bench, ias=10.0)  # past the stall speed: flying
    step(bench, ias=5.0)  # slow again, still flying
    bench.put(ORB_ID.position_setpoint_triplet, PositionSetpointTriplet(
        current=PositionSetpoint(valid=True, type=PositionSetpoint.SETPOINT_TYPE_LAND)))
    step(bench, ias=10.0)  # landing
    step(bench)  # no new sample: the validator is not fed
    assert [c["in_fixed_wing_flight"] for c in fed] == [False, False, True, True, False]


def test_the_wind_estimator_gets_no_velocity_when_dead_reckoning_or_stale(fed):
    bench = ModuleBench(AirspeedSelectorModule)
    position = dict(v_xy_valid=True, vx=12.0, vy=1.0, vz=0.5)
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp_sample=100_000, **position))
    step(bench, ias=15.0)
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp_sample=bench.now, dead_reckoning=True,
                                                                  **position))
    step(bench, ias=15.0)
    bench.put(ORB_ID.vehicle_local_position, VehicleLocalPosition(timestamp_sample=bench.now, **position))
    bench.now += 1_000_000
    step(bench, ias=15.0)
    assert [c["velocity"] for c in fed] == [(12.0, 1.0, 0.5), None, None]


def test_publishes_the_validated_sample_and_a_nan_wind_before_it_starts_stamped_now():
    bench = ModuleBench(AirspeedSelectorModule)
    step(bench, ias=15.0)
    validated = bench.sent(ORB_ID.airspeed_validated)[-1]
    wind = bench.sent(ORB_ID.wind)[-1]
    assert validated.timestamp_sample == wind.timestamp_sample == bench.now
    assert validated.airspeed_sensor_measurement_valid and validated.selected_airspeed_index == 1
    assert validated.indicated_airspeed_m_s == pytest.approx(15.0)
    assert math.isnan(wind.windspeed_north) and math.isnan(validated.true_ground_minus_wind_m_s)


def test_a_stall_speed_change_reaches_the_validator():
    bench = ModuleBench(AirspeedSelectorModule, {"FW_AIRSPD_STALL": 7.0})
    bench.set_param("FW_AIRSPD_STALL", 9.0)
    assert bench.module.validator.params.fw_airspd_stall == 9.0
