"""RateControl (PX4 rate PID), its yaw-torque low-pass and the acro stick mapping."""

import math

import pytest

from stack.attctl.rate_control import (
    AcroStickMapping,
    RateControl,
    YawTorqueLowPass,
    integrator_factor,
    saturation_from_allocator,
)
from stack.mathlib.scalar import FLT_EPSILON

DT = 0.004
ZERO = (0.0, 0.0, 0.0)
NO_SAT = (False, False, False)


def test_torque_is_p_error_plus_integral_minus_d_accel_plus_feedforward():
    rc = RateControl({"MC_ROLLRATE_FF": 0.1})
    torque = rc.update((0.1, 0.0, -0.2), (0.5, 0.2, 0.0), (2.0, -1.0, 3.0), DT, landed=True)
    assert torque == pytest.approx((0.15 * 0.4 - 0.003 * 2.0 + 0.1 * 0.5, 0.15 * 0.2 + 0.003 * 1.0, 0.2 * 0.2))


def test_k_form_scales_p_i_d_but_not_feedforward():
    base = RateControl({"MC_ROLLRATE_FF": 0.1})
    doubled = RateControl({"MC_ROLLRATE_FF": 0.1, "MC_ROLLRATE_K": 2.0})
    args = ((0.0, 0.0, 0.0), (0.5, 0.0, 0.0), (1.0, 0.0, 0.0), DT, False)
    t1 = base.update(*args)[0]
    t2 = doubled.update(*args)[0]
    ff = 0.1 * 0.5
    assert t2 - ff == pytest.approx(2.0 * (t1 - ff))
    assert doubled.integral[0] == pytest.approx(2.0 * base.integral[0])


def test_integrator_accumulates_with_forward_euler_and_is_clamped():
    rc = RateControl()
    rc.update(ZERO, (0.5, 0.0, -0.5), ZERO, DT, False)
    f = integrator_factor(0.5)
    assert rc.integral == pytest.approx((f * 0.2 * 0.5 * DT, 0.0, -f * 0.1 * 0.5 * DT))
    for _ in range(20000):
        rc.update(ZERO, (0.5, 0.0, -0.5), ZERO, DT, False)
    assert rc.integral == pytest.approx((0.3, 0.0, -0.3))
    rc.reset_integral()
    assert rc.integral == ZERO


def test_i_factor_values():
    assert integrator_factor(math.radians(100.0)) == pytest.approx(0.9375)
    assert integrator_factor(math.radians(200.0)) == pytest.approx(0.75)
    assert integrator_factor(math.radians(-200.0)) == pytest.approx(0.75)
    assert integrator_factor(math.radians(400.0)) == 0.0
    assert integrator_factor(math.radians(600.0)) == 0.0


def test_large_rate_error_integrates_less():
    rc = RateControl()
    rc.update(ZERO, (math.radians(200.0), 0.0, 0.0), ZERO, DT, False)
    assert rc.integral[0] == pytest.approx(0.75 * 0.2 * math.radians(200.0) * DT)


def test_saturated_axis_stops_winding_up_that_way_but_still_unwinds():
    rc = RateControl()
    for _ in range(100):
        rc.update(ZERO, (1.0, 0.0, 0.0), ZERO, DT, False)
    wound = rc.integral[0]
    assert wound > 0.0
    rc.set_saturation_status((True, False, False), NO_SAT)
    for _ in range(100):
        rc.update(ZERO, (1.0, 0.0, 0.0), ZERO, DT, False)
    assert rc.integral[0] == wound
    rc.update(ZERO, (-1.0, 0.0, 0.0), ZERO, DT, False)
    assert rc.integral[0] < wound
    # Negative saturation on pitch blocks only negative integration there.
    rc.set_saturation_status(NO_SAT, (False, True, False))
    rc.update(ZERO, (0.0, -1.0, 0.0), ZERO, DT, False)
    assert rc.integral[1] == 0.0
    rc.update(ZERO, (0.0, 1.0, 0.0), ZERO, DT, False)
    assert rc.integral[1] > 0.0


def test_saturation_flags_from_the_allocator_status():
    # An achieved torque never saturates, whatever is left over.
    assert saturation_from_allocator(True, (0.5, -0.5, 0.5)) == (NO_SAT, NO_SAT)
    # Otherwise the sign of each axis's unallocated torque, beyond FLT_EPSILON.
    tiny = 0.5 * FLT_EPSILON
    assert saturation_from_allocator(False, (0.2, -0.3, tiny)) == ((True, False, False), (False, True, False))
    assert saturation_from_allocator(False, (-tiny, 0.0, -0.1)) == (NO_SAT, (False, False, True))


def test_no_integration_when_landed():
    rc = RateControl()
    for _ in range(50):
        rc.update(ZERO, (1.0, 1.0, 1.0), ZERO, DT, landed=True)
    assert rc.integral == ZERO


def test_nan_setpoint_holds_the_current_rate():
    rc = RateControl({"MC_PITCHRATE_FF": 0.2})
    rate = (0.3, -0.4, 0.1)
    torque = rc.update(rate, (math.nan, math.nan, 0.1), (0.0, 1.0, 0.0), DT, False)
    assert torque == pytest.approx((0.0, -0.003 * 1.0 + 0.2 * -0.4, 0.0))
    assert rc.integral == ZERO


def test_non_finite_results_are_zero_and_do_not_corrupt_the_integrator():
    rc = RateControl()
    rc.update(ZERO, (0.5, 0.5, 0.5), ZERO, DT, False)
    before = rc.integral
    torque = rc.update((math.nan, 0.0, math.inf), (0.5, 0.5, 0.5), ZERO, DT, False)
    assert torque[0] == 0.0 and torque[2] == 0.0 and math.isfinite(torque[1])
    assert rc.integral[0] == before[0] and rc.integral[2] == before[2]


def test_yaw_torque_low_pass_has_the_configured_cutoff():
    lpf = YawTorqueLowPass(2.0)
    alpha = DT / (DT + 1.0 / (2.0 * math.pi * 2.0))
    assert lpf.update(1.0, DT) == pytest.approx(alpha)
    tau = 1.0 / (2.0 * math.pi * 2.0)
    for _ in range(round(tau / DT) - 1):
        y = lpf.update(1.0, DT)
    assert y == pytest.approx(1.0 - math.exp(-1.0), abs=0.02)
    off = YawTorqueLowPass(0.0)
    assert off.update(0.7, DT) == 0.7
    lpf.reset()
    assert lpf.update(0.0, DT) == 0.0


def test_acro_stick_signs_and_scaling():
    acro = AcroStickMapping()  # 100 °/s on every axis, linear
    full = math.radians(100.0)
    assert acro.rates(1.0, 0.0, 0.0) == pytest.approx((full, 0.0, 0.0))
    # Pitch stick forward (+1) is nose down: negative body pitch rate.
    assert acro.rates(0.0, 1.0, 0.0) == pytest.approx((0.0, -full, 0.0))
    assert acro.rates(0.0, 0.0, -0.5) == pytest.approx((0.0, 0.0, -0.5 * full))
    assert AcroStickMapping.thrust_body(-1.0) == (0.0, 0.0, -0.0)
    assert AcroStickMapping.thrust_body(0.0) == (0.0, 0.0, -0.5)
    assert AcroStickMapping.thrust_body(1.0) == (0.0, 0.0, -1.0)


def test_acro_expo_and_superexpo():
    acro = AcroStickMapping({"MC_ACRO_EXPO": 1.0, "MC_ACRO_R_MAX": 720.0, "MC_ACRO_SUPEXPOY": 0.7})
    # Cubic expo: half stick gives an eighth of the rate; full stick still the full rate.
    assert acro.rates(0.5, 0.0, 0.0)[0] == pytest.approx(math.radians(720.0) / 8.0)
    assert acro.rates(1.0, 0.0, 0.0)[0] == pytest.approx(math.radians(720.0))
    # Super-expo on yaw only: (1 − g)/(1 − |x|·g) at half stick.
    assert acro.rates(0.0, 0.0, 0.5)[2] == pytest.approx(math.radians(100.0) * 0.5 * 0.3 / 0.65)
