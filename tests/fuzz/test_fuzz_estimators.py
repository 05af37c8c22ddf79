"""Fuzz the estimators' updates with any sensor values: nothing raises, and the estimate stays finite (a sample
that is not finite is dropped) or, for what is not known yet, NaN."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from stack.estimator.attitude_q import AttitudeEstimatorQ
from stack.estimator.position_kf import LocalPositionKF
from stack.msg.sensors import SensorGps
from tests.fuzz.strategies import FUZZ, all_finite, any_int, finite_or_nan, nasty_float, quat, vec3

LEVEL = (1.0, 0.0, 0.0, 0.0)
REST = (0.0, 0.0, -9.80665)


@FUZZ
@given(
    samples=st.lists(
        st.tuples(nasty_float, vec3, vec3, st.one_of(st.none(), vec3), st.one_of(st.none(), vec3)),
        min_size=1,
        max_size=4,
    ),
    initial=st.one_of(st.none(), quat),
)
def test_the_attitude_estimator_takes_any_imu_and_mag_sample(samples, initial):
    estimator = AttitudeEstimatorQ()
    estimator.reset(initial)
    estimator.update(0.004, (0.0, 0.0, 0.0), REST, (0.2, 0.0, 0.4))
    for dt, gyro, accel, mag, compensation in samples:
        estimator.update(dt, gyro, accel, mag, compensation)
        assert all_finite(estimator.q) and all_finite(estimator.rates) and all_finite(estimator.gyro_bias)


gps = st.builds(
    SensorGps,
    timestamp_sample=st.integers(0, 2**40),
    latitude_deg=nasty_float,
    longitude_deg=nasty_float,
    altitude_msl_m=nasty_float,
    fix_type=any_int,
    eph=nasty_float,
    epv=nasty_float,
    vel_n_m_s=nasty_float,
    vel_e_m_s=nasty_float,
    vel_d_m_s=nasty_float,
    vel_ned_valid=st.booleans(),
    satellites_used=any_int,
)
events = st.one_of(
    st.tuples(st.just("predict"), st.integers(-(10**6), 10**6), vec3, st.one_of(st.just(LEVEL), quat)),
    st.tuples(st.just("baro"), nasty_float),
    st.tuples(st.just("gps"), gps),
)


@FUZZ
@given(steps=st.lists(events, min_size=1, max_size=6))
def test_the_position_filter_takes_any_imu_baro_and_gps_sample(steps):
    kf = LocalPositionKF()
    t = 1_000_000
    for step in steps:
        if step[0] == "predict":
            t += step[1]
            kf.predict(t, step[2], step[3])
        elif step[0] == "baro":
            kf.fuse_baro(step[1])
        else:
            kf.fuse_gps(step[1])
        est = kf.estimate()
        for value in (*est.position, *est.velocity, est.ref_lat, est.ref_lon, est.ref_alt, est.alt):
            assert finite_or_nan(value), est
        assert all_finite(est.accel_bias)
