import math
import random

import pytest

from stack.fw.wind_estimator import WindEstimator, WindEstimatorParams
from stack.mathlib.quaternion import from_euler

DEFAULTS = WindEstimatorParams()
AIRSPEED = 15.0
RADIUS = 80.0
OMEGA = AIRSPEED / RADIUS
ROLL = math.atan(AIRSPEED * OMEGA / 9.80665)
DT_US = 20_000


def circle(wind, t):
    """A coordinated clockwise circle at 15 m/s airspeed in a constant wind: ground velocity and attitude."""
    psi = OMEGA * t
    velocity = (AIRSPEED * math.cos(psi) + wind[0], AIRSPEED * math.sin(psi) + wind[1], 0.0)
    return velocity, from_euler(ROLL, 0.03, psi)


def test_defaults():
    assert WindEstimatorParams(0.1, 0.0001, 1.4, 0.3, 3.0, 1.0) == DEFAULTS


def test_starts_from_the_heading_and_the_first_airspeed():
    # w = v − TAS·(cos ψ, sin ψ); the covariance: TAS noise along the heading, heading and sideslip
    # uncertainty (10°, 15°) times TAS across it, plus the velocity variance.
    estimator = WindEstimator(DEFAULTS)
    estimator.fuse_airspeed(1, 15.0, (20.0, 5.0, 0.0), 0.04, from_euler(0.0, 0.0, 0.0))
    assert estimator.initialised and estimator.reset_this_step
    assert estimator.wind == pytest.approx((5.0, 5.0))
    lateral = 15.0**2 * (math.radians(10.0) ** 2 + math.radians(15.0) ** 2)
    assert estimator.wind_variance == pytest.approx((1.4**2 + 0.04, lateral + 0.04))
    assert estimator.tas_scale == 1.0


def test_covariance_grows_once_a_second_without_measurements():
    estimator = WindEstimator(DEFAULTS)
    estimator.fuse_airspeed(1, 15.0, (15.0, 0.0, 0.0), 0.04, from_euler(0.0, 0.0, 0.0))
    before = estimator.wind_variance
    estimator.update(900_001)
    assert estimator.wind_variance == before
    estimator.update(2_000_001)
    assert estimator.wind_variance == pytest.approx((before[0] + (0.1 * 2.0) ** 2, before[1] + (0.1 * 2.0) ** 2))


@pytest.mark.parametrize("wind", [(3.0, -4.0), (0.0, 8.0), (-8.0, 0.0)])
def test_converges_to_a_constant_wind_on_a_circle(wind):
    # A 10 % airspeed scale error and a start 20° off in heading: within 45 s the wind is within 1 m/s
    # and stays there (one circle takes 34 s), and the scale estimate moves toward 1/1.1.
    rng = random.Random(3)
    estimator = WindEstimator(DEFAULTS)
    errors = []
    for i in range(120 * 50):
        t_us = DT_US * i + 1
        velocity, q = circle(wind, t_us * 1e-6)
        start_error = from_euler(ROLL, 0.03, math.radians(20.0)) if i == 0 else q
        estimator.update(t_us)
        estimator.fuse_airspeed(t_us, 1.1 * AIRSPEED + rng.gauss(0.0, 0.3), velocity, 0.05, start_error)
        estimator.fuse_beta(t_us, velocity, 0.05, q)
        errors.append((t_us * 1e-6, math.dist(estimator.wind, wind)))
    assert errors[0][1] > 2.0
    assert max(e for t, e in errors if t >= 45.0) < 1.0
    assert max(e for t, e in errors if t >= 90.0) < 0.6
    assert estimator.tas_scale < 0.94


def test_an_outlier_is_gated_and_a_lasting_inconsistency_restarts_the_filter():
    wind = (3.0, -4.0)
    estimator = WindEstimator(DEFAULTS)
    for i in range(30 * 50):
        t_us = DT_US * i + 1
        velocity, q = circle(wind, t_us * 1e-6)
        estimator.update(t_us)
        estimator.fuse_airspeed(t_us, AIRSPEED, velocity, 0.05, q)
        estimator.fuse_beta(t_us, velocity, 0.05, q)
    state = list(estimator.state)
    t_us += 100_000
    first_outlier_us = t_us
    velocity, q = circle(wind, t_us * 1e-6)
    estimator.fuse_airspeed(t_us, AIRSPEED + 20.0, velocity, 0.05, q)
    assert estimator.tas_innov == pytest.approx(20.0, abs=0.5)
    assert estimator.state == state  # 20 m/s is far outside 3 standard deviations
    restarted_at = None
    for _ in range(7 * 50):
        t_us += DT_US
        velocity, q = circle(wind, t_us * 1e-6)
        estimator.update(t_us)
        estimator.fuse_airspeed(t_us, AIRSPEED + 20.0, velocity, 0.05, q)
        if estimator.reset_this_step and restarted_at is None:
            restarted_at = t_us
    assert restarted_at is not None and 5.0 < (restarted_at - first_outlier_us) * 1e-6 <= 5.1


def test_non_finite_inputs_are_ignored():
    estimator = WindEstimator(DEFAULTS)
    estimator.fuse_airspeed(1, math.nan, (15.0, 0.0, 0.0), 0.04, from_euler(0.0, 0.0, 0.0))
    estimator.fuse_beta(1, (math.nan, 0.0, 0.0), 0.04, from_euler(0.0, 0.0, 0.0))
    assert not estimator.initialised
