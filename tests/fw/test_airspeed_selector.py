"""The airspeed checks (library) and the airspeed_selector module, in process and in lockstep, against a
scripted circle flight in wind."""

from __future__ import annotations

import dataclasses
import math
import random
from pathlib import Path

import pytest

from stack.fw.airspeed_validator import AirspeedValidator, AirspeedValidatorParams
from stack.mathlib.quaternion import from_euler, rotate_inv
from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.msg.estimation import VehicleAttitude, VehicleLocalPosition
from stack.msg.fixedwing import Airspeed
from stack.msg.registry import ORB_ID
from stack.msg.system import VehicleLandDetected
from stack.runtime.inprocess import InProcessStack
from stack.runtime.module import Arg, Module
from stack.supervisor.profile import load_profile

DEFAULTS = AirspeedValidatorParams()
AIRSPEED = 15.0
OMEGA = AIRSPEED / 80.0
ROLL = math.atan(AIRSPEED * OMEGA / G)
WIND = (3.0, -4.0)


def circle(t: float):
    """Ground velocity, NED acceleration and attitude of a coordinated clockwise circle in WIND."""
    psi = OMEGA * t
    velocity = (AIRSPEED * math.cos(psi) + WIND[0], AIRSPEED * math.sin(psi) + WIND[1], 0.0)
    accel = (-AIRSPEED * OMEGA * math.sin(psi), AIRSPEED * OMEGA * math.cos(psi), 0.0)
    return velocity, accel, from_euler(ROLL, 0.0, psi)


def fly(validator: AirspeedValidator, start_s: float, end_s: float, indicated=lambda t: AIRSPEED):
    """Feed the validator 20 Hz samples of the circle; returns the first time [s] it found the airspeed invalid."""
    invalid_at = None
    for i in range(round(start_s * 20), round(end_s * 20)):
        t = i / 20.0
        velocity, accel, q = circle(t)
        accel_z = rotate_inv(q, (accel[0], accel[1], accel[2] - G))[2]
        ias = indicated(t)
        validator.update(
            round(t * 1e6) + 1,
            ias,
            ias,
            in_fixed_wing_flight=True,
            velocity=velocity,
            velocity_var_ne=0.05,
            q=q,
            accel_z=accel_z,
        )
        if not validator.valid and invalid_at is None:
            invalid_at = t
    return invalid_at


def test_a_consistent_sensor_stays_valid():
    validator = AirspeedValidator(DEFAULTS)
    assert fly(validator, 0.0, 60.0) is None
    assert math.dist(validator.wind_estimator.wind, WIND) < 0.3
    # n/(V/V_stall)² = 1.02/4.6, held at the filter's floor of 0.25.
    assert 1.0 / math.cos(ROLL) / (15.0 / 7.0) ** 2 < 0.25 == validator.load_factor_ratio


def test_missing_data_invalidates_at_once_and_for_good():
    validator = AirspeedValidator(DEFAULTS)
    validator.check_timeout(5_000_000)
    assert validator.valid  # no data yet: nothing missing
    fly(validator, 0.0, 1.0)
    validator.check_timeout(1_950_001)
    assert validator.valid
    validator.check_timeout(2_050_001)
    assert not validator.valid
    assert fly(validator, 3.0, 10.0) == 3.0  # ASPD_FS_T_START −1: not in this flight


def test_data_returning_is_used_again_after_the_start_delay():
    validator = AirspeedValidator(dataclasses.replace(DEFAULTS, aspd_fs_t_start=3))
    fly(validator, 0.0, 1.0)
    validator.check_timeout(2_100_001)
    fly(validator, 3.0, 5.0)
    assert not validator.valid
    fly(validator, 5.0, 5.5)
    assert validator.valid  # 3 s after the failure


def test_an_airspeed_too_low_to_lift_the_plane_is_invalid():
    # 30 % of the airspeed: (4.5/7)² of the stall lift cannot carry a load factor of 1.1.
    validator = AirspeedValidator(DEFAULTS)
    assert fly(validator, 0.0, 20.0) is None
    failed_at = fly(validator, 20.0, 40.0, indicated=lambda t: 0.3 * AIRSPEED)
    assert failed_at is not None and failed_at - 20.0 < 3.5
    assert validator.load_factor_check_failed


def test_an_inconsistent_airspeed_fails_the_innovation_check():
    # A sudden +12 m/s error, after the estimator has settled: the test ratio (12²/(3²·var)) exceeds
    # ASPD_FS_INNOV, its integral ASPD_FS_INTEG within a second; failed 1 s later, invalid 2 s after that.
    validator = AirspeedValidator(DEFAULTS)
    assert fly(validator, 0.0, 20.0) is None
    failed_at = fly(validator, 20.0, 24.5, indicated=lambda t: AIRSPEED + 12.0)
    assert failed_at is not None and 3.0 < failed_at - 20.0 < 4.5
    assert validator.innovations_check_failed and not validator.load_factor_check_failed


def test_without_checks_only_missing_data_counts():
    validator = AirspeedValidator(dataclasses.replace(DEFAULTS, aspd_do_checks=0))
    assert fly(validator, 0.0, 20.0, indicated=lambda t: 0.3 * AIRSPEED) is None


# -- the module, in process -----------------------------------------------------------------------------


class CircleFlight(Module):
    """Lockstep clock at 50 Hz: the estimator's outputs of a circle flight in WIND and a 20 Hz airspeed
    sensor that stops at ``dropout_s``; records what airspeed_selector publishes."""

    NAME = "circle_flight"
    PUBLISHES = (ORB_ID.airspeed, ORB_ID.vehicle_local_position, ORB_ID.vehicle_attitude, ORB_ID.vehicle_land_detected)
    LOCKSTEP_COORDINATOR = True
    ARGS = (Arg("dropout_s", 0.0), Arg("takeoff_s", 0.0), Arg("steps", 0))

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.airspeed,
            ORB_ID.vehicle_local_position,
            ORB_ID.vehicle_attitude,
            ORB_ID.vehicle_land_detected,
        ):
            self.advertise(topic)
        self.subscribe(ORB_ID.airspeed_validated)
        self.subscribe(ORB_ID.wind)
        self.rng = random.Random(rt.spec.seed)
        self.step = 0
        self.received: list[tuple[float, object, object]] = []

    def step_period_us(self) -> int:
        return 20_000

    def run(self, msg: object, dt: float) -> None:
        self.step += 1
        now = self.now_us()
        t = now * 1e-6
        velocity, accel, q = circle(t)
        self.publish(
            ORB_ID.vehicle_local_position,
            VehicleLocalPosition(
                timestamp_sample=now,
                v_xy_valid=True,
                v_z_valid=True,
                vx=velocity[0],
                vy=velocity[1],
                vz=velocity[2],
                ax=accel[0],
                ay=accel[1],
                az=accel[2],
                evh=0.2,
                evv=0.2,
            ),
        )
        self.publish(ORB_ID.vehicle_attitude, VehicleAttitude(timestamp_sample=now, q=q))
        self.publish(ORB_ID.vehicle_land_detected, VehicleLandDetected(landed=False, maybe_landed=False))
        if self.step % 3 == 0 and t < float(self.args["dropout_s"]):
            # Below the stall speed until takeoff_s: the takeoff run, no wind estimation yet.
            ias = AIRSPEED if t >= float(self.args["takeoff_s"]) else 5.0
            ias += self.rng.gauss(0.0, 0.2)
            measured = Airspeed(timestamp_sample=now, indicated_airspeed_m_s=ias, true_airspeed_m_s=ias)
            self.publish(ORB_ID.airspeed, measured)
        self.received.append((t, self.latest(ORB_ID.airspeed_validated), self.latest(ORB_ID.wind)))
        if self.step >= int(self.args["steps"]):
            raise SystemExit(0)


def test_the_module_estimates_the_wind_and_drops_a_silent_sensor(tmp_path: Path):
    profile = tmp_path / "circle.toml"
    profile.write_text(
        """
[stack]
vehicle = "t1"
lockstep = true
seed = 5

[[module]]
module = "tests.fw.test_airspeed_selector:CircleFlight"
args = { dropout_s = 60.0, takeoff_s = 2.0, steps = 3100 }
critical = true

[[module]]
module = "airspeed_selector"
"""
    )
    stack = InProcessStack(load_profile(profile))
    flight = stack.coordinator.module
    stack.run()
    received = flight.received
    at_1s = next(r for r in received if r[0] >= 1.0)
    assert at_1s[1].airspeed_sensor_measurement_valid  # valid on the ground too
    assert math.isnan(at_1s[2].windspeed_north)  # but no wind before the takeoff run is over
    at_40s = next(r for r in received if r[0] >= 40.0)
    validated, wind = at_40s[1], at_40s[2]
    assert validated.selected_airspeed_index == 1
    assert validated.indicated_airspeed_m_s == pytest.approx(AIRSPEED, abs=0.8)
    assert validated.true_airspeed_m_s == validated.indicated_airspeed_m_s
    assert math.dist((wind.windspeed_north, wind.windspeed_east), WIND) < 0.5
    assert validated.true_ground_minus_wind_m_s == pytest.approx(AIRSPEED, abs=0.5)
    assert 0.0 < wind.variance_north < 1.0
    # Silent from 60 s: invalid 1 s later, its speeds NaN.
    last = received[-1]
    assert last[0] == pytest.approx(62.0)
    assert not last[1].airspeed_sensor_measurement_valid and last[1].selected_airspeed_index == -1
    assert math.isnan(last[1].indicated_airspeed_m_s) and math.isnan(last[1].true_airspeed_m_s)
    first_invalid = next(r[0] for r in received if r[0] > 60.0 and not r[1].airspeed_sensor_measurement_valid)
    assert 61.0 < first_invalid <= 61.2
