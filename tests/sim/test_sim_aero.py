"""Flat-plate segments (PX4 SIH's AeroSeg, Khan & Nahon) against hand-worked figures."""

from __future__ import annotations

import itertools
import math

import pytest

from stack.airframe.model import propeller_thrust
from stack.mathlib.atmosphere import AIR_DENSITY_SEA_LEVEL as RHO
from stack.sim.aero import AeroSegment, flat_plate_stall_angle, lift_slope, slipstream_speed

DEG = math.pi / 180.0


def tailplane(**kw: object) -> AeroSegment:
    """The SIH airplane's tailplane: 0.3 × 0.1 m (AR 3) at x = −0.4 m, elevator chord 0.05 m."""
    args: dict = {"flap_chord": 0.05}
    args.update(kw)
    return AeroSegment(0.3, 0.1, (-0.4, 0.0, 0.0), **args)


def test_lift_slope_is_the_aspect_ratio_corrected_flat_plate_slope() -> None:
    # AR = 0.86/0.21 = 4.0952: 2π / (1 + 2·8.0952/(4.0952·6.0952)) = 6.28319 / 1.64862
    assert lift_slope(0.86 / 0.21) == pytest.approx(3.81118, rel=1e-5)
    # AR 3 (the tailplane): 2π / (1 + 14/15)
    assert lift_slope(3.0) == pytest.approx(2.0 * math.pi / (1.0 + 14.0 / 15.0))
    # A very long wing has the thin-airfoil slope 2π.
    assert lift_slope(1e6) == pytest.approx(2.0 * math.pi, rel=1e-5)


def test_small_angle_lift_and_drag_of_a_plain_plate() -> None:
    seg = tailplane(flap_chord=0.0)
    a = 0.02
    cl, cd, cm = seg.coefficients(a)
    # Attached flow: C_L = k_p·s·c² + π·s²·c = 3.24992·0.0199987·0.9996 + π·0.00039995·0.9998
    assert cl == pytest.approx(0.066225, rel=1e-4)
    # ≈ the thin-airfoil figure k_p·α (the vortex lift adds π·α²).
    assert cl == pytest.approx(lift_slope(3.0) * a + math.pi * a * a, rel=1e-3)
    # C_D = C_D0 + |C_L,flat·tan α|: C_N = 1.98·sin α·(1/(0.56 + 0.44|sin α|) − k_n), k_n = 0.41(1 − e^(−17/3))
    # = 0.053437, C_T = 0.02·cos α, C_L,flat = C_N·cos α − C_T·sin α = 0.053026, tan α = 0.0200027.
    assert cd == pytest.approx(0.0410607, rel=1e-4)
    assert cm == pytest.approx(-0.17 * math.pi * math.sin(a) ** 2, rel=1e-3)
    # Zero lift at zero angle, C_D0 alone.
    assert seg.coefficients(0.0) == pytest.approx((0.0, 0.04, 0.0), abs=1e-9)


def test_a_plain_plate_is_antisymmetric_in_angle_of_attack_over_360_degrees() -> None:
    seg = tailplane(flap_chord=0.0)
    for deg in (5, 15, 25, 45, 90, 135, 170):
        cl, cd, _ = seg.coefficients(deg * DEG)
        cl_neg, cd_neg, _ = seg.coefficients(-deg * DEG)
        assert cl_neg == pytest.approx(-cl, abs=1e-12)
        assert cd_neg == pytest.approx(cd, abs=1e-12)
        assert cd > 0.0


def test_at_90_degrees_the_plate_has_no_lift_and_the_flat_plate_drag() -> None:
    seg = tailplane(flap_chord=0.0)
    cl, cd, _ = seg.coefficients(math.pi / 2)
    kn = 0.41 * (1.0 - math.exp(-17.0 / 3.0))
    assert cl == pytest.approx(0.0, abs=1e-9)
    assert cd == pytest.approx(1.98 * (1.0 - kn), rel=1e-6)  # 1.17101: C_D90 reduced for the finite span


def test_stall_the_lift_peaks_near_the_stall_angle_and_falls_beyond_it() -> None:
    seg = tailplane(flap_chord=0.0)
    stall = seg.stall_angle_max
    assert math.degrees(stall) == pytest.approx(25.0)  # Khan's table at AR 3
    lifts = [(seg.coefficients(d * 0.1 * DEG)[0], d * 0.1) for d in range(0, 900)]
    cl_max, at = max(lifts)
    assert abs(at - math.degrees(stall)) < 5.0
    assert seg.coefficients(stall + 10 * DEG)[0] < 0.8 * cl_max
    # Continuous through the 10° blend (steep, but no jump between neighbouring tenths of a degree).
    assert max(abs(b[0] - a[0]) for a, b in itertools.pairwise(lifts)) < 0.03


def test_flat_plate_stall_table_interpolates_in_aspect_ratio() -> None:
    assert math.degrees(flat_plate_stall_angle(0.86 / 0.21)) == pytest.approx(24.0 - (0.0952381 / 2.0) * 2.0)
    assert math.degrees(flat_plate_stall_angle(0.1)) == 49.0
    assert math.degrees(flat_plate_stall_angle(10.0)) == 22.0


def test_flap_deflection_adds_lift_as_the_flap_effectiveness_fit_says() -> None:
    seg = tailplane()
    delta = 15 * DEG
    seg.set_deflection(delta)
    # c_f/c = 0.5: θ_f = acos(0) = π/2, τ_f = 1 − (π/2 − 1)/π = 0.818310;
    # η_f = 0.0535·δ² − 0.2688·δ + 0.5817 = 0.514995 at δ = 0.261799 rad.
    tau_f = 1.0 - (math.pi / 2 - 1.0) / math.pi
    eta_f = 0.0535 * delta**2 - 0.2688 * delta + 0.5817
    assert eta_f == pytest.approx(0.514995, rel=1e-5)
    delta_cl = lift_slope(3.0) * tau_f * eta_f * delta  # 0.35856
    cl, _, _ = seg.coefficients(0.0)
    assert cl == pytest.approx(delta_cl, rel=2e-3)  # three Newton steps find the shifted zero-lift angle
    seg.set_deflection(-delta)
    assert seg.coefficients(0.0)[0] == pytest.approx(-cl, rel=1e-6)


def test_slipstream_speed_from_momentum_theory() -> None:
    # √(2T/(ρπr²)) = √(4 / (1.225·π·0.01)) = √103.94
    assert slipstream_speed(2.0, RHO, 0.1) == pytest.approx(10.1951, rel=1e-4)
    assert slipstream_speed(0.0, RHO, 0.1) == 0.0


def test_propeller_thrust_of_the_advance_ratio_model() -> None:
    ct = (0.131, 0.004, -0.146)  # UIUC APC 8x6"
    # Static, full throttle, 13000 RPM, D = 0.2032 m: 0.131·ρ·(216.667)²·0.2032⁴ = 12.844 N
    assert propeller_thrust(1.0, 0.0, RHO, 0.2032, 13000.0, ct) == pytest.approx(12.844, rel=1e-3)
    # 15 m/s: J = 15/(216.667·0.2032) = 0.34070, C_T = 0.131 + 0.004·J − 0.146·J² = 0.115416
    assert propeller_thrust(1.0, 15.0, RHO, 0.2032, 13000.0, ct) == pytest.approx(11.316, rel=1e-3)
    # Quarter throttle halves the speed of rotation: a quarter of the static thrust.
    assert propeller_thrust(0.25, 0.0, RHO, 0.2032, 13000.0, ct) == pytest.approx(12.844 / 4, rel=1e-3)
    # Past the advance ratio where C_T reaches 0 it does not windmill.
    assert propeller_thrust(0.01, 30.0, RHO, 0.2032, 13000.0, ct) == 0.0
    assert propeller_thrust(0.0, 0.0, RHO, 0.2032, 13000.0, ct) == 0.0


def test_segment_force_and_moment_about_the_cg() -> None:
    seg = tailplane(flap_chord=0.0)
    u, w = 15.0, 15.0 * math.tan(2 * DEG)  # 2° angle of attack
    fx, fy, fz, mx, my, mz = seg.wrench(u, 0.0, w, 0.0, 0.0, 0.0, RHO)
    cl, cd, cm = seg.coefficients(2 * DEG)
    q = 0.5 * RHO * (u * u + w * w)
    a = 2 * DEG
    assert fx == pytest.approx(q * 0.03 * (cl * math.sin(a) - cd * math.cos(a)))
    assert fz == pytest.approx(q * 0.03 * (-cl * math.cos(a) - cd * math.sin(a)))
    assert fy == 0.0 and mx == 0.0 and mz == 0.0
    # The tail lifts behind the CG: a nose-down moment, 0.4·F_z plus the plate's own C_M.
    assert my == pytest.approx(0.4 * fz + q * 0.03 * 0.1 * cm)
    assert my < 0.0


def test_a_pitch_rate_changes_the_tail_angle_of_attack() -> None:
    seg = tailplane(flap_chord=0.0)
    # Nose-up rate: the tail moves down, sees the air from below, lifts and damps the rate.
    _, _, fz, _, my, _ = seg.wrench(15.0, 0.0, 0.0, 0.0, 1.0, 0.0, RHO)
    assert fz < 0.0 and my < 0.0


def test_fin_sideslip_gives_a_side_force_and_a_weathervane_yaw() -> None:
    fin = AeroSegment(0.25, 0.18, (-0.45, 0.0, -0.1), dihedral=-90 * DEG, flap_chord=0.12)
    # Air from the right (the body moves right relative to the air): v > 0.
    _, fy, fz, mx, _, mz = fin.wrench(15.0, 1.0, 0.0, 0.0, 0.0, 0.0, RHO)
    assert fy < 0.0  # pushed to the left
    assert mz > 0.0  # the nose turns right, into the relative wind
    # The plate's angle of attack is the sideslip angle atan(1/15); its "lift" is along body −y, its own
    # pitching moment about its span axis (body −z for the fin).
    alpha = math.atan2(1.0, 15.0)
    cl, cd, cm = fin.coefficients(alpha)
    q_s = 0.5 * RHO * (15.0**2 + 1.0) * 0.25 * 0.18
    assert fy == pytest.approx(-q_s * (cl * math.cos(alpha) + cd * math.sin(alpha)))
    assert mz == pytest.approx(-0.45 * fy - q_s * 0.18 * cm)
    assert mx == pytest.approx(0.1 * fy)  # −p_z·F_y: pushed left above the CG, the plane rolls left
    assert abs(fz) < 1e-12
    # A positive rudder flap (more "lift" on the fin, to the left at the tail) yaws right too.
    fin.set_deflection(10 * DEG)
    assert fin.wrench(15.0, 0.0, 0.0, 0.0, 0.0, 0.0, RHO)[5] > 0.0


def test_below_a_tenth_of_a_metre_per_second_no_force() -> None:
    assert tailplane().wrench(0.05, 0.0, 0.05, 0.0, 0.0, 0.0, RHO) == (0.0,) * 6
