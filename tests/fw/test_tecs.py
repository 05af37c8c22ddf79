import dataclasses
import math

import pytest

from stack.fw.tecs import Tecs, TecsMode, TecsParams
from stack.mathlib.scalar import CONSTANTS_ONE_G as G

DEFAULTS = TecsParams()
# Pure proportional paths, for the hand-worked numbers.
BARE = dataclasses.replace(DEFAULTS, fw_t_thr_damp=0.0, fw_t_i_gain_thr=0.0, fw_t_i_gain_pit=0.0)
TRIM = 0.6
PITCH_LIMIT = math.radians(45.0)


def step(tecs, dt=0.02, **kw):
    state = dict(
        altitude=100.0,
        vz=0.0,
        vz_valid=True,
        az=0.0,
        airspeed=15.0,
        speed_derivative=0.0,
        eas_to_tas=1.0,
        pitch=0.0,
        roll=0.0,
        altitude_sp=100.0,
        airspeed_sp=15.0,
        pitch_min=-PITCH_LIMIT,
        pitch_max=PITCH_LIMIT,
        throttle_min=0.0,
        throttle_max=1.0,
        throttle_trim=TRIM,
    )
    state.update(kw)
    return tecs.update(dt, **state)


def test_the_parameters_are_the_catalogue_definitions():
    assert DEFAULTS.fw_t_clmb_max == 5.0 and DEFAULTS.fw_t_sink_min == 2.0 and DEFAULTS.fw_airspd_trim == 15.0


def test_at_the_setpoint_trim_throttle_and_level_pitch():
    tecs = Tecs(DEFAULTS)
    for _ in range(200):
        out = step(tecs)
    assert out.throttle_sp == pytest.approx(TRIM, abs=1e-12)
    assert out.pitch_sp == pytest.approx(0.0, abs=1e-12)
    assert out.mode is TecsMode.NORMAL
    status = tecs.status()
    assert status.throttle_integ == 0.0 and status.pitch_integ == 0.0


def test_a_climb_demand_raises_throttle_and_pitch():
    # Height rate 2 m/s: SPĖ_sp = 2g splits into throttle 0.6 + 2g/(5g)·(1 − 0.6) and
    # pitch (1 + 0.1)·2g/(g·15) (feed-forward plus damping of the balance rate error).
    tecs = Tecs(BARE)
    out = step(tecs, dt=0.2, altitude_sp=math.nan, height_rate_sp=2.0)
    assert out.throttle_sp == pytest.approx(TRIM + 2.0 / 5.0 * 0.4)
    assert out.pitch_sp == pytest.approx(0.2 * 7.0 / 15.0)  # the vertical acceleration limit on pitch
    out = step(tecs, dt=0.2, altitude_sp=math.nan, height_rate_sp=2.0)
    assert out.pitch_sp == pytest.approx(1.1 * 2.0 / 15.0)


def test_an_altitude_demand_raises_throttle_and_pitch_within_the_climb_limit():
    tecs = Tecs(DEFAULTS)
    for _ in range(100):
        out = step(tecs, altitude_sp=150.0)
    assert out.throttle_sp > TRIM and out.pitch_sp > 0.0
    assert 0.0 < tecs.status().height_rate_setpoint <= DEFAULTS.fw_t_clmb_max
    tecs = Tecs(DEFAULTS)
    for _ in range(100):
        out = step(tecs, altitude_sp=50.0)
    assert out.throttle_sp < TRIM and out.pitch_sp < 0.0
    assert -DEFAULTS.fw_t_sink_max <= tecs.status().height_rate_setpoint < 0.0


def test_a_speed_demand_raises_throttle_and_lowers_pitch():
    # V̇_sp = (18 − 15)/5 = 0.6 m/s², SKĖ_sp = 15·0.6 = 9 m²/s³: throttle 0.6 + 9/(5g)·0.4, and the
    # balance rate −9 pitches down by 1.1·9/(15g).
    tecs = Tecs(BARE)
    out = step(tecs, dt=0.2, airspeed_sp=18.0)
    assert out.throttle_sp == pytest.approx(TRIM + 9.0 / (5.0 * G) * 0.4)
    assert out.pitch_sp == pytest.approx(-1.1 * 9.0 / (15.0 * G))
    assert tecs.status().true_airspeed_derivative_sp == pytest.approx(0.6)


def test_speed_rate_demand_is_limited_to_half_the_throttle_authority():
    # (20 − 10)/2 = 5 m/s² asked; full throttle gives 5g m²/s³, half of it 2.5g/10 m/s².
    tecs = Tecs(dataclasses.replace(BARE, fw_t_tas_tc=2.0))
    step(tecs, dt=0.2, airspeed_sp=20.0, airspeed=10.0)
    assert tecs.status().true_airspeed_derivative_sp == pytest.approx(0.5 * 5.0 * G / 10.0)
    tecs.reset()
    step(tecs, dt=0.2, airspeed_sp=10.0, airspeed=20.0)
    assert tecs.status().true_airspeed_derivative_sp == pytest.approx(-0.5 * 2.0 * G / 20.0)


def test_turns_ask_for_more_energy():
    # Roll 60°: load factor 2, FW_T_RLL2THR·(2 − 1) = 15 m²/s³ more total energy rate.
    tecs = Tecs(BARE)
    out = step(tecs, roll=math.radians(60.0))
    assert out.throttle_sp == pytest.approx(TRIM + 15.0 / (5.0 * G) * 0.4)
    assert out.pitch_sp == pytest.approx(0.0, abs=1e-12)


def test_outputs_stay_within_their_limits_and_pitch_is_rate_limited():
    tecs = Tecs(DEFAULTS)
    last_pitch = 0.0
    for _ in range(500):
        out = step(tecs, altitude_sp=1000.0, airspeed_sp=25.0, pitch_max=0.3, throttle_max=0.9)
        assert 0.0 <= out.throttle_sp <= 0.9
        assert -PITCH_LIMIT <= out.pitch_sp <= 0.3
        assert abs(out.pitch_sp - last_pitch) <= 0.02 * DEFAULTS.fw_t_vert_acc / 15.0 + 1e-12
        last_pitch = out.pitch_sp
    assert out.throttle_sp == 0.9 and out.pitch_sp == 0.3
    tecs = Tecs(DEFAULTS)
    for _ in range(500):
        out = step(tecs, altitude_sp=-1000.0, throttle_min=0.1, pitch_min=-0.2)
    assert out.throttle_sp == 0.1 and out.pitch_sp == -0.2


def test_climbout_full_throttle_and_at_least_the_climbout_pitch():
    tecs = Tecs(DEFAULTS)
    pitch_min = math.radians(10.0)
    for _ in range(200):
        out = step(tecs, altitude_sp=200.0, climbout=True, climbout_pitch_min=pitch_min)
    assert out.mode is TecsMode.CLIMBOUT
    assert out.throttle_sp >= 1.0 - 0.01
    assert out.pitch_sp == pytest.approx(pitch_min)
    # Faster than demanded: pitch speed control raises the nose above the minimum,
    # by 1.1·(17 · 0.4)/(17g) (the balance rate is the kinetic energy rate alone).
    tecs = Tecs(BARE)
    for _ in range(200):
        out = step(tecs, altitude_sp=200.0, airspeed=17.0, climbout=True, climbout_pitch_min=pitch_min)
    assert out.pitch_sp == pytest.approx(pitch_min + 1.1 * 17.0 * 0.4 / (17.0 * G))


@pytest.mark.parametrize(("airspeed", "ratio"), [(9.0, 0.0), (7.75, 0.0), (6.625, 0.5), (5.5, 1.0), (4.0, 1.0)])
def test_the_underspeed_ratio_ramps_in_below_the_minimum_airspeed(airspeed: float, ratio: float):
    # FW_AIRSPD_MIN 10, trim 15 (PX4 v1.14): none above 10 − 0.15·15 = 7.75 m/s, full below 10 − 0.3·15 = 5.5 m/s.
    tecs = Tecs(DEFAULTS)
    out = step(tecs, airspeed=airspeed)
    assert tecs.status().underspeed_ratio == pytest.approx(ratio)
    assert out.mode is (TecsMode.UNDERSPEED if ratio > 0.0 else TecsMode.NORMAL)


def test_underspeed_blends_throttle_towards_its_maximum_and_pitch_towards_speed():
    # Half undersped at 6.625 m/s and asked to climb, asking for the minimum airspeed (so the setpoint blend
    # changes nothing).
    normal, undersped = Tecs(BARE), Tecs(BARE)
    kw = dict(airspeed=6.625, airspeed_sp=10.0, altitude_sp=110.0, throttle_max=0.7)
    for _ in range(50):
        off = step(normal, detect_underspeed=False, **kw)
        on = step(undersped, **kw)
    assert on.throttle_sp == pytest.approx(0.5 * 0.7 + 0.5 * off.throttle_sp)
    # The speed weight 1 goes half way to 2: the climb counts half in the balance, the nose stays lower.
    status = undersped.status()
    ske_rate_sp = status.true_airspeed_filtered * status.true_airspeed_derivative_sp
    assert status.total_energy_balance_rate_sp == pytest.approx(0.5 * G * status.height_rate_setpoint - ske_rate_sp)
    assert on.pitch_sp < off.pitch_sp


def test_full_underspeed_gives_full_throttle_the_minimum_airspeed_and_holds_the_throttle_integrator():
    tecs = Tecs(DEFAULTS)
    for _ in range(50):
        out = step(tecs, airspeed=5.0, airspeed_sp=15.0, throttle_max=0.7)
    assert out.mode is TecsMode.UNDERSPEED
    assert out.throttle_sp == 0.7
    assert tecs.status().true_airspeed_sp == DEFAULTS.fw_airspd_min
    assert tecs.status().throttle_integ == 0.0
    out = step(tecs, airspeed=5.0, airspeed_sp=15.0, throttle_max=0.7, detect_underspeed=False)
    assert out.mode is TecsMode.NORMAL and tecs.status().underspeed_ratio == 0.0


def test_without_airspeed_pitch_holds_height_and_throttle_is_open_loop():
    tecs = Tecs(DEFAULTS)
    for _ in range(100):
        out = step(tecs, airspeed=math.nan, airspeed_sp=18.0)
    # Flying the trim airspeed: the speed demand goes to throttle (predicted only), not to pitch.
    assert out.throttle_sp == pytest.approx(TRIM + 15.0 * 0.6 / (5.0 * G) * 0.4)
    assert out.pitch_sp == pytest.approx(0.0, abs=1e-12)
    assert tecs.status().throttle_integ == 0.0


def test_on_the_ground_nothing_is_controlled_and_reset_restarts():
    tecs = Tecs(DEFAULTS)
    out = step(tecs, in_air=False, pitch=0.1, throttle_min=0.05)
    assert out == (0.1, 0.05, TecsMode.NORMAL)
    for _ in range(300):
        step(tecs, altitude_sp=120.0)
    assert tecs.status().throttle_integ != 0.0
    tecs.reset()
    step(tecs)
    assert tecs.status().pitch_integ == 0.0
    assert abs(tecs.status().throttle_integ) < 1e-4


def test_the_baro_inertial_filter_tracks_a_steady_climb():
    # No estimator vertical velocity: height and rate from the altitude alone (az = 0, a ramp).
    tecs = Tecs(DEFAULTS)
    for i in range(1000):
        step(tecs, altitude=100.0 + 2.0 * 0.02 * i, vz=math.nan, vz_valid=False, altitude_sp=200.0)
    assert tecs.status().height_rate == pytest.approx(2.0, abs=0.01)


def test_non_finite_inputs_do_not_break_it():
    tecs = Tecs(DEFAULTS)
    out = step(tecs, dt=math.nan, airspeed_sp=math.nan, eas_to_tas=0.0, roll=math.nan, pitch=math.nan)
    assert math.isfinite(out.pitch_sp) and math.isfinite(out.throttle_sp)
