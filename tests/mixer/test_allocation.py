"""Rotor effectiveness and PX4's multirotor allocation with sequential desaturation."""

import math

import numpy as np
import pytest

from stack.attctl.rate_control import saturation_from_allocator
from stack.mixer.allocation import (
    MINIMUM_YAW_MARGIN,
    AllocationResult,
    ControlAllocator,
    desaturate,
    normalized_allocation,
    thrust_has_priority,
)
from stack.mixer.effectiveness import effectiveness_from_params, rotor_effectiveness
from stack.msg.system import VehicleLandDetected

# SIH quad X in PX4 motor order: (x, y, KM); KM > 0 is counter-clockwise.
QUAD_X = [(1.0, 1.0, 0.05), (-1.0, -1.0, 0.05), (1.0, -1.0, -0.05), (-1.0, 1.0, -0.05)]
# m_r, m_p, m_y per motor: PX4's normalised pseudo-inverse (ControlAllocationPseudoInverse.cpp) of this geometry.
QUAD_X_TABLE = [(-0.7071, 0.7071, 1.0), (0.7071, -0.7071, 1.0), (0.7071, 0.7071, -1.0), (-0.7071, -0.7071, -1.0)]
HOVER = (0.0, 0.0, -0.5)
NO_SAT = (False, False, False)


def rate_saturation(r: AllocationResult) -> tuple[tuple[bool, ...], tuple[bool, ...]]:
    """The (positive, negative) saturation the rate controller reads from this allocation's status."""
    return saturation_from_allocator(r.torque_achieved, r.unallocated_torque)


def rotor_params(rotors, **extra):
    p = {"CA_ROTOR_COUNT": len(rotors), **extra}
    for i, (x, y, km) in enumerate(rotors):
        p[f"CA_ROTOR{i}_PX"] = x
        p[f"CA_ROTOR{i}_PY"] = y
        p[f"CA_ROTOR{i}_KM"] = km
    return p


def quad(airmode=0) -> ControlAllocator:
    return ControlAllocator.from_params(rotor_params(QUAD_X, MC_AIRMODE=airmode))


def hexa_x() -> ControlAllocator:
    # PX4 hexa X (CA_AIRFRAME 0 with 6 rotors): arms at ±30°, ±90°, ±150°, alternating spin.
    angles = [90.0, -90.0, -30.0, 150.0, 30.0, -150.0]
    km = [-0.05, 0.05, -0.05, 0.05, 0.05, -0.05]
    rotors = [(0.25 * math.cos(math.radians(a)), 0.25 * math.sin(math.radians(a)), k)
              for a, k in zip(angles, km, strict=True)]
    return ControlAllocator.from_params(rotor_params(rotors))


def test_effectiveness_columns():
    b = rotor_effectiveness(np.array([[1.0, 2.0, 0.0]]), np.array([[0.0, 0.0, -2.0]]), np.array([6.5]),
                            np.array([0.05]))
    # p × a = (2·(−1) − 0, 0 − 1·(−1), 0) = (−2, 1, 0); −CT·KM·a = (0, 0, 0.325); thrust CT·a.
    assert b[:, 0] == pytest.approx([-13.0, 6.5, 0.325, 0.0, 0.0, -6.5])
    # A zero axis or a zero CT: the rotor is ignored.
    zero = rotor_effectiveness(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
                               np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]),
                               np.array([6.5, 0.0]), np.array([0.05, 0.05]))
    assert not zero.any()


def test_effectiveness_from_params_uses_px4_defaults_and_checks_the_count():
    b = effectiveness_from_params(rotor_params(QUAD_X))
    assert b.shape == (6, 4)
    assert b[5] == pytest.approx([-6.5] * 4)  # CT 6.5 along the default axis (0, 0, −1)
    with pytest.raises(ValueError):
        effectiveness_from_params({"CA_ROTOR_COUNT": 13})


def test_desaturation_balances_violations_with_a_full_then_a_half_step():
    u = [1.4, -0.2]
    desaturate(u, (1.0, 1.0))
    # k = −0.4 + 0.2 → [1.2, −0.4]; then half of (−0.2 + 0.4) → [1.3, −0.3]: equal overshoot both ends.
    assert u == pytest.approx([1.3, -0.3])
    u = [1.4, 0.5]
    desaturate(u, (1.0, 0.5))
    assert u == pytest.approx([1.0, 0.3])


def test_desaturation_ignores_actuators_with_weak_effect_and_can_be_reduce_only():
    u = [1.5, 0.5]
    desaturate(u, (0.1, 1.0))
    assert u == [1.5, 0.5]
    u = [-0.3, 0.5]
    desaturate(u, (-1.0, -1.0), reduce_only=True)  # would need a negative gain: left alone
    assert u == [-0.3, 0.5]


def test_quad_x_matches_the_px4_table():
    mix = quad().mix
    for motor, (m_r, m_p, m_y) in enumerate(QUAD_X_TABLE):
        assert mix[motor, 0:3] == pytest.approx([m_r, m_p, m_y], abs=1e-4)
        assert mix[motor, 5] == pytest.approx(-1.0)
        assert mix[motor, 3] == 0.0 and mix[motor, 4] == 0.0


def test_pure_roll_torque_on_quad_x():
    r = quad().allocate((0.1, 0.0, 0.0), HOVER)
    delta = [m - 0.5 for m in r.motors]
    assert delta == pytest.approx([-0.07071, 0.07071, 0.07071, -0.07071], abs=1e-5)
    assert sum(delta) == pytest.approx(0.0, abs=1e-12)  # no thrust change
    assert r.allocated_torque == pytest.approx((0.1, 0.0, 0.0), abs=1e-12)
    assert r.allocated_thrust == pytest.approx(HOVER, abs=1e-12)
    assert r.torque_achieved and r.thrust_achieved
    assert r.actuator_saturation == (0, 0, 0, 0)
    assert rate_saturation(r) == (NO_SAT, NO_SAT)


def test_roll_and_pitch_keep_priority_over_yaw():
    r = quad().allocate((0.3, 0.2, 1.0), HOVER)
    assert r.unallocated_torque[0] == pytest.approx(0.0, abs=1e-6)
    assert r.unallocated_torque[1] == pytest.approx(0.0, abs=1e-6)
    assert r.unallocated_torque[2] > 0.1
    assert not r.torque_achieved
    assert rate_saturation(r) == ((False, False, True), NO_SAT)
    assert all(0.0 <= m <= 1.0 for m in r.motors)


def test_thrust_is_reduced_to_keep_roll_at_full_throttle():
    r = quad(airmode=0).allocate((0.3, 0.0, 0.0), (0.0, 0.0, -0.95))
    assert r.allocated_torque[0] == pytest.approx(0.3, abs=1e-6)
    assert r.allocated_thrust[2] > -0.95  # less upward thrust than asked for
    assert r.unallocated_thrust[2] < 0.0
    assert max(r.motors) == pytest.approx(1.0)
    assert not r.thrust_achieved


def test_yaw_margin_gives_yaw_authority_at_full_thrust():
    # Yaw is desaturated against 115 % of the range, then thrust (only) is reduced to fit.
    r = quad(airmode=0).allocate((0.0, 0.0, 0.1), (0.0, 0.0, -1.0))
    assert r.allocated_torque[2] == pytest.approx(0.1, abs=1e-9)
    assert r.allocated_thrust[2] == pytest.approx(-0.9, abs=1e-9)
    assert r.motors == pytest.approx((1.0, 1.0, 0.8, 0.8))


def test_without_airmode_thrust_is_never_raised_and_roll_is_cut_instead():
    r = quad(airmode=0).allocate((0.5, 0.0, 0.0), (0.0, 0.0, -0.1))
    assert r.allocated_thrust[2] >= -0.1 - 1e-9
    assert r.allocated_torque[0] < 0.5 - 0.1
    positive, negative = rate_saturation(r)
    assert positive[0] and not negative[0]
    assert min(r.motors) == 0.0


@pytest.mark.parametrize("airmode", [1, 2])
def test_airmode_raises_thrust_to_keep_roll_authority(airmode):
    r = quad(airmode=airmode).allocate((0.5, 0.0, 0.0), (0.0, 0.0, -0.1))
    assert r.allocated_torque[0] == pytest.approx(0.5, abs=1e-6)
    assert r.allocated_thrust[2] < -0.1 - 0.1  # more upward thrust than asked for
    assert all(0.0 <= m <= 1.0 for m in r.motors)


def test_yaw_airmode_keeps_yaw_at_low_thrust():
    without = quad(airmode=1).allocate((0.0, 0.0, 0.4), (0.0, 0.0, -0.1))
    rpy = quad(airmode=2).allocate((0.0, 0.0, 0.4), (0.0, 0.0, -0.1))
    assert rpy.allocated_torque[2] == pytest.approx(0.4, abs=1e-6)
    assert without.allocated_torque[2] < 0.4 - 0.1


def test_yaw_airmode_takes_full_thrust_for_yaw_only_within_the_yaw_margin():
    # A heading correction in a downdraft at full tilt must not take the thrust that holds the height.
    r = quad(airmode=2).allocate((0.0, 0.0, 0.4), (0.0, 0.0, -1.0))
    assert r.allocated_thrust[2] == pytest.approx(-(1.0 - MINIMUM_YAW_MARGIN), abs=1e-9)
    assert r.allocated_torque[2] == pytest.approx(MINIMUM_YAW_MARGIN, abs=1e-9)
    assert r == quad(airmode=1).allocate((0.0, 0.0, 0.4), (0.0, 0.0, -1.0))


@pytest.mark.parametrize("airmode", [1, 2])
@pytest.mark.parametrize("torque", [(0.5, 0.0, 0.0), (0.0, 0.0, 0.4)])
def test_with_thrust_priority_torque_never_raises_the_thrust(airmode, torque):
    # A vehicle tipping onto its legs must not be lifted off by airmode's added thrust.
    r = quad(airmode=airmode).allocate(torque, (0.0, 0.0, -0.1), thrust_priority=True)
    assert r.allocated_thrust[2] >= -0.1 - 1e-9
    assert r == quad(airmode=0).allocate(torque, (0.0, 0.0, -0.1))


def test_saturation_codes_at_the_limits():
    a = quad()
    idle = a.allocate((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert idle.motors == (0.0, 0.0, 0.0, 0.0) and idle.actuator_saturation == (-2, -2, -2, -2)
    full = a.allocate((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    assert full.actuator_saturation == (2, 2, 2, 2)
    negative_roll = a.allocate((-0.5, 0.0, 0.0), (0.0, 0.0, -0.1))
    positive, negative = rate_saturation(negative_roll)
    assert negative[0] and not positive[0]


def test_hexa_x_allocation():
    a = hexa_x()
    for torque in ((0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1), (0.05, -0.04, 0.03)):
        r = a.allocate(torque, HOVER)
        assert r.torque_achieved and r.thrust_achieved
        assert r.allocated_torque == pytest.approx(torque, abs=1e-9)
        assert sum(m - 0.5 for m in r.motors) == pytest.approx(0.0, abs=1e-9)
    # Yaw: the three counter-clockwise rotors speed up alike, the clockwise ones slow down alike.
    yaw = a.allocate((0.0, 0.0, 0.1), HOVER).motors
    ccw = [yaw[i] for i in (1, 3, 4)]
    cw = [yaw[i] for i in (0, 2, 5)]
    assert ccw == pytest.approx([0.6] * 3) and cw == pytest.approx([0.4] * 3)
    # The two side rotors carry the most roll.
    roll = [m - 0.5 for m in a.allocate((0.1, 0.0, 0.0), HOVER).motors]
    assert roll[0] == pytest.approx(-roll[1]) and abs(roll[0]) == pytest.approx(max(abs(x) for x in roll))


def test_weak_rows_are_dropped():
    # With KM 0.001 the yaw entries (CT·KM = 0.0065) are below 0.05: yaw is not controlled.
    weak = rotor_params([(x, y, math.copysign(0.001, km)) for x, y, km in QUAD_X])
    a = ControlAllocator.from_params(weak)
    assert not a.mix[:, 2].any()
    r = a.allocate((0.0, 0.0, 0.3), HOVER)
    assert r.motors == pytest.approx((0.5, 0.5, 0.5, 0.5))


def test_normalization_cancels_thrust_coefficient_and_arm_length():
    small = effectiveness_from_params(rotor_params([(0.2 * x, 0.2 * y, km) for x, y, km in QUAD_X]))
    mix_small, scale_small = normalized_allocation(small * 0.5)
    mix_ref, scale_ref = normalized_allocation(effectiveness_from_params(rotor_params(QUAD_X)))
    assert mix_small == pytest.approx(mix_ref)
    assert scale_small != pytest.approx(scale_ref)


def test_thrust_has_priority_while_descending_and_on_the_ground():
    assert not thrust_has_priority(None)
    flying = {"ground_contact": False, "maybe_landed": False, "landed": False, "in_descend": False}
    assert not thrust_has_priority(VehicleLandDetected(**flying))
    for flag in flying:
        assert thrust_has_priority(VehicleLandDetected(**{**flying, flag: True})), flag
