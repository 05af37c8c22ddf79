"""PX4 v1.13 fw_att_control (the ECL roll, pitch, yaw and wheel controllers) against hand-worked cases."""

import math

import pytest

from stack.fw.att_control import (
    AttitudeTarget,
    FixedwingAttitudeController,
    RateLoop,
    StickMapping,
    coordinated_turn_rate,
    euler_rates_to_body,
)
from stack.mathlib import quaternion as quat

G = 9.80665
LEVEL = quat.from_euler(0.0, 0.0, 0.0)
STILL = (0.0, 0.0, 0.0)
DT = 0.004
LOCKED_DT = 0.03
"""A step longer than 20 ms: the integrators hold, so an output is its P and FF terms alone."""


def controller(**params) -> FixedwingAttitudeController:
    return FixedwingAttitudeController(params)


def level_target(roll=0.0, pitch=0.0, yaw=0.0, wheel=False) -> AttitudeTarget:
    return AttitudeTarget(roll, pitch, yaw, wheel)


def test_rate_setpoint_is_the_angle_error_over_the_time_constant():
    c = controller(FW_R_TC=0.5, FW_P_TC=0.4)
    out = c.attitude(LEVEL, STILL, level_target(roll=0.2, pitch=0.1), 15.0, DT, landed=False)
    # Level: the Jacobian is the identity; roll 0.2/0.5, pitch 0.1/0.4; no bank set, so no turn rate.
    assert out.rates_sp == pytest.approx((0.4, 0.25, 0.0))


def test_rate_setpoints_stay_within_their_limits():
    c = controller(FW_R_RMAX=70.0, FW_P_RMAX_POS=60.0, FW_P_RMAX_NEG=30.0, FW_Y_RMAX=50.0)
    up = c.attitude(LEVEL, STILL, level_target(roll=1.5, pitch=1.0), 15.0, DT, landed=False)
    assert up.rates_sp[0] == pytest.approx(math.radians(70.0))
    assert up.rates_sp[1] == pytest.approx(math.radians(60.0))
    down = c.attitude(LEVEL, STILL, level_target(roll=-1.5, pitch=-1.0), 15.0, DT, landed=False)
    assert down.rates_sp[:2] == pytest.approx((-math.radians(70.0), -math.radians(30.0)))
    # 80° of bank held at the stall speed: the turn asks ψ̇ = g·tan 80° / 7 = 7.95 rad/s, r = cos 80°·ψ̇ = 1.38 rad/s.
    bank = math.radians(80.0)
    steep = c.attitude(quat.from_euler(bank, 0.0, 0.0), STILL, level_target(roll=bank), 7.0, DT, landed=False)
    assert steep.rates_sp[2] == pytest.approx(math.radians(50.0))


def test_outputs_stay_within_plus_minus_one():
    c = controller()
    out = c.attitude(LEVEL, (-30.0, 30.0, -30.0), level_target(roll=1.0, pitch=-1.0), 15.0, DT, landed=False)
    assert out.torque == (1.0, -1.0, 1.0)


def test_the_rate_loop_is_feed_forward_plus_p_plus_integrator():
    c = controller(FW_RR_P=0.05, FW_RR_FF=0.5, FW_RR_I=0.1)
    out = c.rates((0.1, 0.0, 0.0), (0.5, 0.0, 0.0), 15.0, DT, landed=False)
    # At the trim airspeed s = 1: 0.5·0.5 + (0.5 − 0.1)·0.05 + 0.4·0.004·0.1.
    assert c.integrals[0] == pytest.approx(0.4 * DT * 0.1)
    assert out.torque[0] == pytest.approx(0.25 + 0.02 + 0.00016)


def test_the_integrators_stop_at_their_limits():
    c = controller(FW_RR_IMAX=0.2, FW_PR_IMAX=0.4, FW_YR_IMAX=0.2, FW_RR_I=0.2, FW_PR_I=0.2, FW_YR_I=0.2,
                   FW_RR_FF=0.0, FW_PR_FF=0.0, FW_YR_FF=0.0, FW_RR_P=0.0, FW_PR_P=0.0, FW_YR_P=0.0)
    for _ in range(2000):
        # 0.5 rad/s of error with no P or FF: the outputs are the integrators alone, growing 0.0004 a step.
        c.rates(STILL, (0.5, -0.5, 0.5), 15.0, DT, landed=False)
    assert c.integrals[:3] == pytest.approx((0.2, -0.4, 0.2))


def test_an_output_beyond_its_limit_does_not_wind_the_integrator_further():
    loop = RateLoop(k_p=10.0, k_i=0.5, k_ff=0.0, integrator_max=1.0)
    assert loop.update(1.0, 0.0, 1.0, DT, False) == 1.0  # unclamped 10 + 0.002
    first = loop.integrator
    for _ in range(100):
        loop.update(1.0, 0.0, 1.0, DT, False)
    assert loop.integrator == pytest.approx(first)
    loop.update(-1.0, 0.0, 1.0, DT, False)  # the error turns: the integrator may move back
    assert loop.integrator < first


def test_twice_the_trim_airspeed_gives_a_quarter_of_p_and_half_of_the_feed_forward():
    p_only = {"FW_RR_P": 0.05, "FW_RR_FF": 0.0, "FW_AIRSPD_MAX": 40.0}
    ff_only = {"FW_RR_P": 0.0, "FW_RR_FF": 0.5, "FW_AIRSPD_MAX": 40.0}
    error = (0.0, 0.0, 0.0), (0.4, 0.0, 0.0)
    p_trim = controller(**p_only).rates(*error, 15.0, LOCKED_DT, landed=False).torque[0]
    p_fast = controller(**p_only).rates(*error, 30.0, LOCKED_DT, landed=False).torque[0]
    ff_trim = controller(**ff_only).rates(*error, 15.0, LOCKED_DT, landed=False).torque[0]
    ff_fast = controller(**ff_only).rates(*error, 30.0, LOCKED_DT, landed=False).torque[0]
    assert p_trim == pytest.approx(0.4 * 0.05)
    assert p_fast == pytest.approx(p_trim / 4.0)
    assert ff_trim == pytest.approx(0.4 * 0.5)
    assert ff_fast == pytest.approx(ff_trim / 2.0)


def test_airspeed_scaling_clamps_the_speed_and_falls_back_to_trim():
    c = controller(FW_AIRSPD_TRIM=15.0, FW_AIRSPD_STALL=7.0, FW_AIRSPD_MAX=20.0)
    assert c.airspeed(30.0) == pytest.approx((30.0, 15.0 / 20.0))  # above the maximum: the maximum's scaling
    assert c.airspeed(3.0) == pytest.approx((3.0, 15.0 / 7.0))  # below stall: the stall speed's
    assert c.airspeed(0.1) == pytest.approx((0.5, 15.0 / 7.0))  # never below 0.5 m/s
    assert c.airspeed(math.nan) == (15.0, 1.0)  # no valid airspeed: fly on the trim airspeed's scaling
    assert controller(FW_ARSP_SCALE_EN=False).airspeed(30.0) == (30.0, 1.0)


def test_coordinated_turn_rate_at_30_degrees_and_15_metres_per_second():
    bank = math.radians(30.0)
    assert coordinated_turn_rate(bank, 0.0, bank, 15.0, 7.0) == pytest.approx(0.3774581, abs=1e-6)
    assert G * math.tan(bank) / 15.0 == pytest.approx(0.3774581, abs=1e-6)
    # cos θ: climbing at 20°.
    assert coordinated_turn_rate(bank, math.radians(20.0), bank, 15.0, 7.0) == pytest.approx(
        0.3774581 * math.cos(math.radians(20.0)), abs=1e-6)
    # The bank counts only up to the bank asked for; the speed at least airspeed_min.
    assert coordinated_turn_rate(bank, 0.0, math.radians(10.0), 15.0, 7.0) == pytest.approx(
        G * math.tan(math.radians(10.0)) / 15.0)
    assert coordinated_turn_rate(bank, 0.0, bank, 3.0, 7.0) == pytest.approx(G * math.tan(bank) / 7.0)
    assert coordinated_turn_rate(-bank, 0.0, bank, 15.0, 7.0) == pytest.approx(-0.3774581, abs=1e-6)
    assert coordinated_turn_rate(math.radians(120.0), 0.0, bank, 15.0, 7.0) is None  # inverted


def test_euler_rates_become_body_rates_through_the_ecl_jacobian():
    bank = math.radians(30.0)
    # A level turn (φ̇ = θ̇ = 0) at 30° bank: q = sin φ·ψ̇, r = cos φ·ψ̇.
    assert euler_rates_to_body(bank, 0.0, (0.0, 0.0, 0.4)) == pytest.approx((0.0, 0.2, 0.4 * math.sqrt(3) / 2))
    # Pitched 20° up, wings level: p = φ̇ − sin θ·ψ̇, q = θ̇, r = cos θ·ψ̇.
    pitch = math.radians(20.0)
    assert euler_rates_to_body(0.0, pitch, (0.1, 0.2, 0.3)) == pytest.approx(
        (0.1 - math.sin(pitch) * 0.3, 0.2, math.cos(pitch) * 0.3))
    # Banked 30°: a pitch Euler rate tilts into −r.
    assert euler_rates_to_body(bank, 0.0, (0.0, 0.2, 0.0)) == pytest.approx((0.0, 0.2 * math.sqrt(3) / 2, -0.1))


def test_a_held_30_degree_turn_asks_the_coordinated_body_rates():
    bank = math.radians(30.0)
    c = controller()
    out = c.attitude(quat.from_euler(bank, 0.0, 1.0), STILL, level_target(roll=bank, yaw=2.0), 15.0, DT, landed=False)
    yaw_rate = G * math.tan(bank) / 15.0
    assert out.rates_sp == pytest.approx((0.0, 0.5 * yaw_rate, math.sqrt(3) / 2 * yaw_rate))


def test_integrators_restart_on_the_ground_and_hold_when_slow_or_late():
    c = controller()
    rates = (STILL, (0.5, 0.5, 0.5))
    c.rates(*rates, 15.0, DT, landed=False)
    flying = c.integrals
    assert all(i > 0.0 for i in flying[:3])
    c.rates(*rates, 15.0, DT, landed=True)
    assert c.integrals == (0.0, 0.0, 0.0, 0.0)
    c.rates(*rates, 15.0, DT, landed=False)
    assert c.integrals == flying
    c.rates(*rates, 4.9, DT, landed=False)  # below half of FW_AIRSPD_MIN (10 m/s): held
    c.rates(*rates, 15.0, LOCKED_DT, landed=False)  # a step over 20 ms: held
    assert c.integrals == flying
    c.rates(*rates, math.nan, DT, landed=False)  # no airspeed: flies on trim, integrates
    assert c.integrals[0] > flying[0]


def test_the_wheel_controller_steers_the_heading_on_the_runway():
    c = controller(FW_W_EN=True, FW_WR_P=0.5, FW_WR_I=0.1, FW_WR_FF=0.2, FW_W_RMAX=30.0, FW_AIRSPD_STALL=7.0)
    heading = quat.from_euler(0.0, 0.0, 0.0)
    out = c.attitude(heading, STILL, level_target(yaw=0.02, wheel=True), math.nan, DT, landed=False, groundspeed=14.0)
    # Rate = 0.02 / 0.1 s = 0.2 rad/s; ground-speed scaling g = 7/14 = 0.5; I = 0.2·0.004·0.5·0.1 = 4e-5;
    # steering = 0.2·0.2·0.5 + 0.25·(0.2·0.5 + 4e-5).
    assert out.rates_sp[2] == pytest.approx(0.2)
    assert c.integrals[3] == pytest.approx(4e-5)
    assert out.torque[2] == pytest.approx(0.02 + 0.25 * (0.1 + 4e-5))
    # A large error, across ±180°: the shorter way, within FW_W_RMAX.
    across = c.attitude(quat.from_euler(0.0, 0.0, -3.1), STILL, level_target(yaw=3.1, wheel=True), math.nan, DT,
                        landed=False, groundspeed=14.0)
    assert across.rates_sp[2] == pytest.approx(-math.radians(30.0))
    # Below 1 m/s of ground speed the integrator holds; below the stall speed the scaling is 1.
    before = c.integrals[3]
    slow = c.attitude(heading, STILL, level_target(yaw=0.02, wheel=True), math.nan, DT, landed=False, groundspeed=0.5)
    assert c.integrals[3] == before
    assert slow.torque[2] == pytest.approx(0.2 * 0.2 + (0.2 * 0.5 + before))


def test_the_wheel_controller_needs_fw_w_en_and_restarts_the_yaw_integrator():
    target = level_target(yaw=0.5, wheel=True)
    off = controller(FW_W_EN=False)
    assert off.attitude(LEVEL, STILL, target, 15.0, DT, landed=False, groundspeed=10.0).rates_sp[2] == 0.0
    on = controller(FW_W_EN=True)
    on.rates(STILL, (0.0, 0.0, 0.5), 15.0, DT, landed=False)
    assert on.integrals[2] > 0.0
    assert on.attitude(LEVEL, STILL, target, 15.0, DT, landed=False, groundspeed=10.0).rates_sp[2] > 0.0
    assert on.integrals[2] == 0.0


def test_non_finite_inputs_are_refused_and_counted():
    c = controller()
    assert c.attitude((math.nan, 0.0, 0.0, 0.0), STILL, level_target(), 15.0, DT, landed=False) is None
    assert c.attitude(LEVEL, (0.0, math.inf, 0.0), level_target(), 15.0, DT, landed=False) is None
    assert c.attitude(LEVEL, STILL, level_target(roll=math.nan), 15.0, DT, landed=False) is None
    assert c.rates(STILL, (0.0, math.nan, 0.0), 15.0, DT, landed=False) is None
    assert c.nonfinite_inputs == 4
    assert c.integrals == (0.0, 0.0, 0.0, 0.0)
    # A NaN heading matters only to the wheel controller.
    assert c.attitude(LEVEL, STILL, level_target(yaw=math.nan), 15.0, DT, landed=False) is not None


def test_acro_rates_are_limited_to_the_acro_maxima():
    c = controller(FW_ACRO_X_MAX=90.0, FW_ACRO_Y_MAX=60.0, FW_ACRO_Z_MAX=45.0)
    out = c.rates(STILL, (10.0, -10.0, 10.0), 15.0, DT, landed=False)
    assert out.rates_sp == pytest.approx((math.pi / 2, -math.pi / 3, math.pi / 4))


def test_sticks_in_manual_stabilized_and_acro():
    sticks = StickMapping({"FW_MAN_R_SC": 0.5, "FW_MAN_P_SC": 1.0, "FW_MAN_Y_SC": 1.0})
    # Manual: straight to the surfaces; stick forward (pitch +) is nose down, so elevator −.
    assert sticks.torque(0.8, 0.4, -0.2) == pytest.approx((0.4, -0.4, -0.2))
    assert sticks.torque(3.0, -3.0, 0.0) == pytest.approx((0.5, 1.0, 0.0))  # sticks beyond ±1 are clamped
    # Stabilized: full right roll is FW_MAN_R_MAX (45°), full forward pitch −FW_MAN_P_MAX, the heading passed on.
    target = sticks.attitude(1.0, 1.0, 0.7)
    assert target == pytest.approx((math.radians(45.0), -math.radians(45.0), 0.7, False))
    # Acro: FW_ACRO_X/Y/Z_MAX 90/90/45 °/s at full stick.
    assert sticks.rates(1.0, -1.0, 0.5) == pytest.approx((math.pi / 2, math.pi / 2, math.pi / 8))
    assert [StickMapping.throttle(t) for t in (-1.0, 0.0, 1.0, 2.0)] == [0.0, 0.5, 1.0, 1.0]
