import math
import random

import pytest

from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.posctl.hover_thrust_estimator import (
    HoverThrustEstimator,
    HoverThrustEstimatorParams,
    ZeroOrderHoverThrustEkf,
)

DT_US = 10_000  # 100 Hz local position


def _fly(estimator, true_hover, seconds, rng, *, start_us=0, velocity=(0.0, 0.0, 0.0), noise=1.5):
    """Feed synthetic hover data: thrust around hover, measured a_z = g·T/Th − g (up) + noise."""
    t = start_us
    estimate = None
    for _ in range(round(seconds * 1e6 / DT_US)):
        t += DT_US
        thrust_up = true_hover + rng.gauss(0.0, 0.05)
        acc_up = G * thrust_up / true_hover - G + rng.gauss(0.0, noise)
        estimate = estimator.update(
            t, armed=True, in_air=True, velocity=velocity, acc_z=-acc_up, thrust_z=-thrust_up
        )
    return estimate, t


@pytest.mark.parametrize(("true_hover", "seed"), [(0.62, 0), (0.38, 1), (0.55, 2)])
def test_converges_from_a_wrong_initial_value(true_hover, seed):
    estimator = HoverThrustEstimator(HoverThrustEstimatorParams(mpc_thr_hover=0.5))
    rng = random.Random(seed)
    estimate, _ = _fly(estimator, true_hover, 20.0, rng)
    assert estimate.hover_thrust == pytest.approx(true_hover, abs=0.01)
    assert estimate.valid
    assert estimate.hover_thrust_var < 0.001
    assert estimate.accel_innov_test_ratio < 1.0


def test_becomes_valid_only_after_two_seconds_of_low_variance():
    estimator = HoverThrustEstimator()
    rng = random.Random(4)
    t = 0
    first_low_var = first_valid = None
    for _ in range(2000):
        estimate, t = _fly(estimator, 0.5, 0.01, rng, start_us=t)
        if first_low_var is None and estimate.hover_thrust_var < 0.001:
            first_low_var = t
        if first_valid is None and estimate.valid:
            first_valid = t
    assert first_low_var is not None and first_valid is not None
    assert first_valid - first_low_var >= 2_000_000


def test_estimate_is_bounded_by_the_allowed_range():
    estimator = HoverThrustEstimator(HoverThrustEstimatorParams(mpc_thr_hover=0.5, hte_thr_range=0.2))
    estimate, _ = _fly(estimator, 0.85, 20.0, random.Random(5))
    assert estimate.hover_thrust == pytest.approx(0.7)


def test_no_estimation_on_the_ground_or_disarmed():
    estimator = HoverThrustEstimator()
    rng = random.Random(6)
    _, t = _fly(estimator, 0.6, 5.0, rng)
    moved = estimator.hover_thrust
    assert moved > 0.55
    landed = estimator.update(t + DT_US, armed=True, in_air=False, velocity=(0, 0, 0), acc_z=0.0, thrust_z=-0.1)
    assert not landed.valid and math.isnan(landed.hover_thrust)
    assert estimator.hover_thrust == moved  # kept while armed on the ground
    estimator.update(t + 2 * DT_US, armed=False, in_air=False, velocity=(0, 0, 0), acc_z=0.0, thrust_z=0.0)
    assert estimator.hover_thrust == 0.5  # reset to MPC_THR_HOVER when disarmed


def test_fast_motion_reduces_the_measurement_weight():
    slow = ZeroOrderHoverThrustEkf(0.5)
    fast = ZeroOrderHoverThrustEkf(0.5)
    fast.set_measurement_noise_scale(4.0)
    for ekf in (slow, fast):
        ekf.predict(0.01)
        ekf.fuse_acc_z(1.0, 0.5)
    assert fast.innov_var > slow.innov_var
    assert abs(fast.hover_thrust - 0.5) < abs(slow.hover_thrust - 0.5)

    # Through the estimator: vertical speed 5 m/s (HTE_VZ_THR 2) scales the noise by 4.
    estimator = HoverThrustEstimator()
    estimator.update(0, armed=True, in_air=True, velocity=(0, 0, 5.0), acc_z=-1.0, thrust_z=-0.5)
    estimate = estimator.update(DT_US, armed=True, in_air=True, velocity=(0, 0, 5.0), acc_z=-1.0, thrust_z=-0.5)
    assert estimate.accel_innov_var == pytest.approx(fast.innov_var, rel=1e-6)


def test_measurement_model_hand_worked():
    ekf = ZeroOrderHoverThrustEkf(0.5)
    ekf.predict(0.01)
    ekf.fuse_acc_z(0.0, 0.6)
    # Predicted a = g·0.6/0.5 − g; the innovation is the negative of it.
    assert ekf.innov == pytest.approx(-(G * 0.6 / 0.5 - G))
    h = -G * 0.6 / 0.25
    p = 0.01 + 12.5e-6 * 0.01**2
    assert ekf.innov_var == pytest.approx(h * p * h + 5.0)
    assert ekf.hover_thrust > 0.5  # less acceleration than predicted → more thrust needed to hover


def test_recovers_after_a_sudden_hover_thrust_change():
    estimator = HoverThrustEstimator(HoverThrustEstimatorParams(hte_thr_range=0.3))
    rng = random.Random(8)
    _, t = _fly(estimator, 0.45, 20.0, rng)
    estimate, _ = _fly(estimator, 0.65, 30.0, rng, start_us=t)
    # The random-walk model with HTE_HT_NOISE 0.0036 tracks slowly: most of the step in 30 s.
    assert estimate.hover_thrust == pytest.approx(0.65, abs=0.025)
    assert estimate.valid
