"""LocalPositionKF on synthetic IMU/GPS/baro data: convergence, tracking, delay, outage, resets, garbage,
and the height reference (EKF2_HGT_REF): baro-referenced z against GPS altitude noise, bias and jumps."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import pytest

from stack.estimator.position_kf import (
    HGT_REF_BARO,
    HGT_REF_GPS,
    X_HGT_OFS,
    X_Z,
    LocalPositionKF,
    PositionEstimatorParams,
)
from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.params import catalogue

LAT0, LON0, ALT0 = 47.397742, 8.545594, 488.0
IMU_DT_US = 4000  # 250 Hz
GPS_EVERY = 31  # IMU steps between GPS fixes (~8 Hz)
BARO_EVERY = 12  # ~20 Hz
T0_US = 5_000_000
GPS_EVERY_10HZ = 25

# The values recommended for launch/sitl_quad.toml: the simulator's GPS fixes carry their true sample
# time, and its barometer is good to 0.09 m (0.2 m leaves margin), where LPE's 3 m default assumes a
# real sensor in prop wash.
SIM_PROFILE = {"lpe_gps_delay": 0.0, "lpe_bar_z": 0.2}


def sim_profile_filter(**params: float) -> LocalPositionKF:
    """The filter with the simulator's sensor parameters (SIM_PROFILE) and ``params``."""
    return LocalPositionKF(PositionEstimatorParams(**{**SIM_PROFILE, **params}))

BOTH_REFS = pytest.mark.parametrize("hgt_ref", (HGT_REF_BARO, HGT_REF_GPS), ids=("baro_ref", "gps_ref"))

Trajectory = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Gps:
    """Satisfies stack.estimator.position_kf.GpsMeasurement."""

    timestamp_sample: int
    latitude_deg: float
    longitude_deg: float
    altitude_msl_m: float
    vel_n_m_s: float
    vel_e_m_s: float
    vel_d_m_s: float
    vel_ned_valid: bool = True
    eph: float = 0.9
    epv: float = 1.78
    fix_type: int = 3
    satellites_used: int = 10


def hover(_t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.zeros(3), np.zeros(3), np.zeros(3)


def circle_with_climb(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2 m/s on a 10 m radius circle, climbing at 0.5 m/s: position, velocity, acceleration NED."""
    speed, radius, climb = 2.0, 10.0, 0.5
    w = speed / radius
    p = np.array((radius * math.sin(w * t), radius * (1.0 - math.cos(w * t)), -climb * t))
    v = np.array((speed * math.cos(w * t), speed * math.sin(w * t), -climb))
    a = np.array((-speed * w * math.sin(w * t), speed * w * math.cos(w * t), 0.0))
    return p, v, a


def takeoff(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """5 s on the ground, a 5 m climb in 5 s (cosine velocity profile), then hover."""
    if t < 5.0:
        return np.zeros(3), np.zeros(3), np.zeros(3)
    if t > 10.0:
        return np.array((0.0, 0.0, -5.0)), np.zeros(3), np.zeros(3)
    s = (t - 5.0) / 5.0
    z = -5.0 * (s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi))
    vz = -1.0 * (1.0 - math.cos(2.0 * math.pi * s))
    az = -0.4 * math.pi * math.sin(2.0 * math.pi * s)
    return np.array((0.0, 0.0, z)), np.array((0.0, 0.0, vz)), np.array((0.0, 0.0, az))


def attitude(t: float) -> Quat:
    """A slowly yawing, slightly tilted vehicle (the filter must use q, whatever it is)."""
    return quat.from_euler(0.08 * math.sin(0.7 * t), -0.05 * math.cos(0.5 * t), 0.3 * t)


@dataclass(frozen=True)
class AirData:
    """A plane's airspeed sensor (TAS noise σ) and the wind and its estimate (off by ``wind_error``)."""

    wind_ned: np.ndarray
    wind_error: tuple[float, float] = (0.0, 0.0)
    wind_var: float = 0.04
    tas_sigma: float = 0.3

    @property
    def wind_estimate(self) -> tuple[float, float]:
        return (self.wind_ned[0] + self.wind_error[0], self.wind_ned[1] + self.wind_error[1])


AIR_DATA_EVERY = 25  # IMU steps: 10 Hz, as airspeed_selector publishes


@dataclass
class Run:
    """Per-prediction ground truth and estimates. ``pos_err`` is in the filter's published frame (its
    z error is the error of the published altitude); ``z`` and ``true_down`` are raw, for heights
    relative to the start."""

    t: np.ndarray
    pos_err: np.ndarray  # (n, 3)
    vel_err: np.ndarray
    eph: np.ndarray
    xy_valid: np.ndarray
    dead_reckoning: np.ndarray
    z_valid: np.ndarray
    z: np.ndarray  # estimated z
    true_down: np.ndarray  # true down position about the start point
    alt: np.ndarray  # published AMSL altitude


def simulate(
    kf: LocalPositionKF,
    seconds: float,
    start_s: float = 0.0,
    trajectory: Trajectory = circle_with_climb,
    seed: int = 0,
    accel_sigma: float = 0.3,
    accel_bias_body: tuple[float, float, float] = (0.0, 0.0, 0.0),
    gps_latency_s: float = 0.0,
    gps_stamp: str = "sample",
    gps_outage: tuple[float, float] | None = None,
    gps_offset_ne: tuple[float, float] = (0.0, 0.0),
    gps_offset_from: float = math.inf,
    gps_every: int = GPS_EVERY,
    gps_alt_sigma: float = 0.5,
    gps_alt_step: tuple[float, float] = (math.inf, 0.0),
    use_gps: bool = True,
    use_baro: bool = True,
    baro_offset: float = 1.5,
    baro_sigma: float = 0.1,
    baro_step: tuple[float, float] = (math.inf, 0.0),
    imu_per_predict: int = 1,
    landed_until: float = 0.0,
    attitude_of: Callable[[float], Quat] = attitude,
    attitude_error: Callable[[float], Quat] | None = None,
    air_data: AirData | None = None,
) -> Run:
    """Drive ``kf`` along ``trajectory`` with noisy sensors; GPS arrives ``gps_latency_s`` late and is
    stamped with its true sample time (``gps_stamp="sample"``) or its arrival time ("arrival").
    ``start_s`` continues an earlier run of the same filter; the baro jumps by ``baro_step[1]`` metres
    from ``baro_step[0]`` seconds on, the GPS altitude likewise with ``gps_alt_step``.
    ``imu_per_predict`` = 5 runs the filter like its module: every 20 ms with the mean accelerometer
    sample, then the baro and GPS samples that arrived meanwhile. Until ``landed_until`` seconds the land
    detector reports landed. ``attitude_of`` gives the attitude at each time, and ``attitude_error`` the
    error of the attitude estimate the filter is given (body frame); with ``air_data`` the true
    airspeed along the body x axis and a wind estimate are fused at 10 Hz."""
    rng = np.random.default_rng(seed)
    truth_map = MapProjection(LAT0, LON0)
    pending: list[tuple[int, Gps]] = []
    baro_queue: list[float] = []
    accel_sum = [0.0, 0.0, 0.0]
    latency_us = round(gps_latency_s * 1e6)
    rows: list[tuple] = []
    first = round(start_s * 1e6 / IMU_DT_US)
    for i in range(first, first + round(seconds * 1e6 / IMU_DT_US)):
        t_us = T0_US + i * IMU_DT_US
        t = (t_us - T0_US) * 1e-6
        p, v, a = trajectory(t)
        q = attitude_of(t)
        f_body = quat.rotate_inv(q, (a[0], a[1], a[2] - CONSTANTS_ONE_G))
        accel = tuple(f_body[k] + accel_bias_body[k] + rng.normal(0.0, accel_sigma) for k in range(3))
        if use_baro and i % BARO_EVERY == 0:
            step = baro_step[1] if t >= baro_step[0] else 0.0
            baro_queue.append(ALT0 - p[2] + baro_offset + step + rng.normal(0.0, baro_sigma))
        in_outage = gps_outage is not None and gps_outage[0] <= t < gps_outage[1]
        if use_gps and i % gps_every == 0 and not in_outage:
            offset = gps_offset_ne if t >= gps_offset_from else (0.0, 0.0)
            north = p[0] + offset[0] + rng.normal(0.0, 0.2)
            east = p[1] + offset[1] + rng.normal(0.0, 0.2)
            lat, lon = truth_map.reproject(north, east)
            vel = v + rng.normal(0.0, (0.06, 0.077, 0.158))
            alt_step = gps_alt_step[1] if t >= gps_alt_step[0] else 0.0
            gps = Gps(t_us, lat, lon, ALT0 - p[2] + alt_step + rng.normal(0.0, gps_alt_sigma), *vel)
            pending.append((t_us + latency_us, gps))
        for k in range(3):
            accel_sum[k] += accel[k]
        if (i + 1) % imu_per_predict != 0:
            continue
        mean = (accel_sum[0] / imu_per_predict, accel_sum[1] / imu_per_predict, accel_sum[2] / imu_per_predict)
        accel_sum = [0.0, 0.0, 0.0]
        if attitude_error is not None:
            q = quat.mul(q, attitude_error(t))
        assert kf.predict(t_us, mean, q)
        for alt in baro_queue:
            kf.fuse_baro(alt)
        baro_queue.clear()
        while pending and pending[0][0] <= t_us:
            arrival, gps = pending.pop(0)
            kf.fuse_gps(gps if gps_stamp == "sample" else replace(gps, timestamp_sample=arrival))
        if t < landed_until:
            kf.fuse_land()
        if air_data is not None and (i + 1) % AIR_DATA_EVERY == 0:
            air = quat.rotate_inv(q, tuple(v - air_data.wind_ned))
            tas = math.sqrt(air[0] ** 2 + air[1] ** 2 + air[2] ** 2) + rng.normal(0.0, air_data.tas_sigma)
            kf.fuse_airspeed(tas, q, air_data.wind_estimate, (air_data.wind_var, air_data.wind_var))

        est = kf.estimate()
        if est.xy_global:
            local_map = MapProjection(est.ref_lat, est.ref_lon)
            true_n, true_e = local_map.project(*truth_map.reproject(p[0], p[1]))
        else:
            true_n, true_e = math.nan, math.nan
        true_z = est.ref_alt - (ALT0 - p[2])
        rows.append(
            (
                t,
                est.position[0] - true_n,
                est.position[1] - true_e,
                est.position[2] - true_z,
                est.velocity[0] - v[0],
                est.velocity[1] - v[1],
                est.velocity[2] - v[2],
                est.eph,
                est.xy_valid,
                est.dead_reckoning,
                est.z_valid,
                est.position[2],
                p[2],
                est.alt,
            )
        )
    arr = np.array(rows, dtype=float)
    return Run(
        t=arr[:, 0],
        pos_err=arr[:, 1:4],
        vel_err=arr[:, 4:7],
        eph=arr[:, 7],
        xy_valid=arr[:, 8].astype(bool),
        dead_reckoning=arr[:, 9].astype(bool),
        z_valid=arr[:, 10].astype(bool),
        z=arr[:, 11],
        true_down=arr[:, 12],
        alt=arr[:, 13],
    )


def rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2)))


def height_error_since(run: Run, t_arm: float) -> np.ndarray:
    """Error of the height change since ``t_arm`` (e.g. arming): (z − z_arm) − (z_true − z_true_arm)."""
    i = int(np.searchsorted(run.t, t_arm))
    return (run.z[i:] - run.z[i]) - (run.true_down[i:] - run.true_down[i])


def flight_like(kf: LocalPositionKF, seconds: float, **kwargs) -> Run:
    """The simulator's sensors (baro σ 0.09 m at 20 Hz, GPS altitude σ 0.5 m at 10 Hz, IMU σ 0.063 m/s²)
    and the module's 20 ms prediction with averaged accelerometer samples, along ``takeoff``."""
    options = {
        "trajectory": takeoff,
        "gps_every": GPS_EVERY_10HZ,
        "baro_sigma": 0.09,
        "baro_offset": 0.0,
        "accel_sigma": 0.063,
        "imu_per_predict": 5,
    } | kwargs
    return simulate(kf, seconds, **options)


def horizontal(run: Run, t_from: float, t_to: float = math.inf) -> np.ndarray:
    sel = (run.t >= t_from) & (run.t < t_to)
    return np.hypot(run.pos_err[sel, 0], run.pos_err[sel, 1])



# ---------------------------------------------------------------------- both height references


@BOTH_REFS
def test_static_convergence(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    run = simulate(kf, 30.0, trajectory=hover)
    est = kf.estimate()
    assert kf.hgt_ref == hgt_ref
    assert est.xy_valid and est.z_valid and est.v_xy_valid and est.v_z_valid
    assert not est.dead_reckoning
    assert est.xy_reset_counter == 1  # the origin was set once
    assert est.z_reset_counter == 0 and est.alt_reset_counter == 0
    assert horizontal(run, 20.0).max() < 0.2
    assert np.abs(run.pos_err[run.t > 20.0, 2]).max() < 0.3
    assert rms(run.vel_err[run.t > 20.0]) < 0.05
    assert est.eph < 1.0 and est.epv < 1.0
    # The global position is the truth; the baro offset (baro altitude − alt) is learned.
    north, east = MapProjection(LAT0, LON0).project(est.lat, est.lon)
    assert math.hypot(north, east) < 0.2
    assert est.alt == pytest.approx(ALT0, abs=0.3)
    assert est.alt == est.ref_alt - est.position[2]
    assert est.baro_offset == pytest.approx(1.5, abs=0.3)


@BOTH_REFS
def test_origin_is_set_at_the_first_good_fixes_without_a_height_jump(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    simulate(kf, 1.0, trajectory=hover, use_gps=False)
    z_before = kf.estimate().position[2]
    assert not kf.estimate().xy_global
    assert math.isnan(kf.estimate().lat)
    run = simulate(kf, 2.0, start_s=1.0, trajectory=hover)
    est = kf.estimate()
    assert est.xy_global and est.z_global
    assert est.ref_lat == pytest.approx(LAT0, abs=1e-5) and est.ref_lon == pytest.approx(LON0, abs=1e-5)
    assert est.xy_reset_counter == 1 and est.vxy_reset_counter == 1 and est.vz_reset_counter == 1
    assert est.z_reset_counter == 0
    assert abs(est.position[2] - z_before) < 0.3
    assert run.z_valid.all()
    # 10 fixes at ~8 Hz are needed before the origin is set.
    first_global = run.t[~np.isnan(run.pos_err[:, 0])][0]
    assert 2.1 < first_global < 2.4


def test_noise_free_origin_gives_the_same_global_altitude_with_either_reference() -> None:
    """Hand-worked: level and still, baro 500 m, GPS 503 m, no noise. The baro defines z = 0; the
    origin puts the 3 m difference into the offset (baro reference: GPS offset +3; GPS reference:
    baro offset −3 and ref_alt 503), so both publish alt 503 and baro_offset −3, exactly."""
    level = quat.IDENTITY
    still = (0.0, 0.0, -CONSTANTS_ONE_G)
    for hgt_ref, offset_state in ((HGT_REF_BARO, 3.0), (HGT_REF_GPS, -3.0)):
        kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
        t = T0_US
        assert kf.predict(t, still, level)
        assert kf.fuse_baro(500.0)
        assert kf.estimate().ref_alt == 500.0 and kf.estimate().position[2] == 0.0
        for i in range(1, 41):
            t += 12_000
            assert kf.predict(t, still, level)
            kf.fuse_baro(500.0)
            if i % 4 == 0:
                kf.fuse_gps(Gps(t, LAT0, LON0, 503.0, 0.0, 0.0, 0.0))
        est = kf.estimate()
        assert est.xy_global and est.z_global and est.z_reset_counter == 0
        assert est.position[2] == 0.0
        assert kf.x[X_HGT_OFS] == offset_state
        assert est.ref_alt == 503.0 and est.alt == 503.0
        assert est.baro_offset == -3.0


@BOTH_REFS
def test_tracks_a_climbing_circle(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    run = simulate(kf, 60.0, accel_bias_body=(0.05, -0.05, 0.1))
    assert run.xy_valid[run.t > 5.0].all() and run.z_valid[run.t > 5.0].all()
    assert rms(horizontal(run, 10.0)) < 0.15
    assert rms(run.pos_err[run.t > 10.0, 2]) < 0.2
    assert rms(run.vel_err[run.t > 10.0, :2]) < 0.06
    assert rms(run.vel_err[run.t > 10.0, 2]) < 0.1
    # The body-frame accelerometer bias is learned while the vehicle yaws.
    assert kf.estimate().accel_bias == pytest.approx((0.05, -0.05, 0.1), abs=0.02)


def test_accel_bias_estimate_is_limited_to_ekf2_abl_lim() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.0, ekf2_abl_lim=0.3))
    simulate(kf, 20.0, trajectory=hover, accel_bias_body=(0.0, 0.0, 1.0))
    assert kf.estimate().accel_bias[2] == 0.3


@BOTH_REFS
def test_delayed_gps_is_fused_at_its_sample_time(hgt_ref: int) -> None:
    latency = 0.25  # 0.5 m of travel at 2 m/s

    def kf(delay: float) -> LocalPositionKF:
        return LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=delay))

    fused_at_sample = simulate(kf(0.0), 40.0, gps_latency_s=latency)
    via_parameter = simulate(kf(latency), 40.0, gps_latency_s=latency, gps_stamp="arrival")
    ignored = simulate(kf(0.0), 40.0, gps_latency_s=latency, gps_stamp="arrival")
    undelayed = simulate(kf(0.0), 40.0)
    err_sample = rms(horizontal(fused_at_sample, 10.0))
    err_param = rms(horizontal(via_parameter, 10.0))
    err_ignored = rms(horizontal(ignored, 10.0))
    err_undelayed = rms(horizontal(undelayed, 10.0))
    assert err_sample < 0.15
    assert err_sample < 1.3 * err_undelayed
    assert err_param == pytest.approx(err_sample, rel=1e-9)
    assert err_ignored > 4.0 * err_sample


@BOTH_REFS
def test_delayed_fusion_equals_fusing_on_time(hgt_ref: int) -> None:
    """Rolling back, fusing and replaying (IMU and baro) is the exact Kalman answer: it matches a
    filter that received every fix without latency, once both have seen the same fixes."""
    latency_steps = 25  # 0.1 s, shorter than the GPS interval
    seconds = (GPS_EVERY * 40 + latency_steps + 1) * IMU_DT_US * 1e-6  # ends on an arrival
    on_time = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    late = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    simulate(on_time, seconds)
    simulate(late, seconds, gps_latency_s=latency_steps * IMU_DT_US * 1e-6)
    assert on_time.x[X_HGT_OFS] != 0.0  # the offset state took part
    np.testing.assert_allclose(late.x, on_time.x, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(late.P, on_time.P, rtol=0.0, atol=1e-9)


@BOTH_REFS
def test_gps_outage_dead_reckons_then_recovers(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    run = simulate(kf, 50.0, gps_outage=(20.0, 30.0), accel_bias_body=(0.02, 0.0, 0.05))
    before = run.t < 20.0
    during = (run.t >= 20.0) & (run.t < 30.0)
    assert not run.dead_reckoning[before].any()
    assert run.dead_reckoning[(run.t > 21.2) & (run.t < 30.0)].all()
    # The uncertainty grows through the outage and the error stays bounded.
    eph = run.eph[during]
    assert eph[-1] > 3.0 * eph[0]
    assert np.all(np.diff(eph) >= 0.0)
    assert horizontal(run, 20.0, 30.0).max() < 1.0
    assert np.abs(run.pos_err[during, 2]).max() < 0.5  # the baro holds the height
    # xy is flagged invalid exactly while eph exceeds LPE_XY_PUB.
    limit = kf.params.lpe_xy_pub
    assert not run.xy_valid[during].all()
    assert np.array_equal(run.xy_valid[during], eph <= limit)
    # GPS is back: the estimate converges without a reset.
    after = run.t > 33.0
    assert run.xy_valid[after].all() and not run.dead_reckoning[after].any()
    assert horizontal(run, 33.0).max() < 0.25
    assert kf.estimate().xy_reset_counter == 1


@BOTH_REFS
def test_persistent_gps_jump_is_rejected_then_reset_to(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    run = simulate(kf, 40.0, gps_offset_ne=(30.0, -40.0), gps_offset_from=20.0)
    # Rejected by the gate for 7 s: the estimate follows the IMU and the consistent GPS velocity.
    assert horizontal(run, 20.0, 26.9).max() < 0.5
    est = kf.estimate()
    assert est.xy_reset_counter == 2  # origin + one reset to the jumped position
    assert est.delta_xy == pytest.approx((30.0, -40.0), abs=0.5)
    assert est.vxy_reset_counter == 1  # the velocity stayed consistent and was never reset
    # After the reset the filter follows the (shifted) GPS.
    shifted = run.pos_err[run.t > 28.0, :2] - np.array((30.0, -40.0))
    assert np.hypot(shifted[:, 0], shifted[:, 1]).max() < 0.3


def climb_10m(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smooth climb of 10 m between t = 5 s and t = 15 s (cosine velocity profile)."""
    if t < 5.0:
        return np.zeros(3), np.zeros(3), np.zeros(3)
    if t > 15.0:
        return np.array((0.0, 0.0, -10.0)), np.zeros(3), np.zeros(3)
    s = (t - 5.0) / 10.0
    z = -10.0 * (s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi))
    vz = -1.0 * (1.0 - math.cos(2.0 * math.pi * s))
    az = -0.2 * math.pi * math.sin(2.0 * math.pi * s)
    return np.array((0.0, 0.0, z)), np.array((0.0, 0.0, vz)), np.array((0.0, 0.0, az))


@BOTH_REFS
def test_baro_only_altitude(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref))
    run = simulate(kf, 25.0, trajectory=climb_10m, use_gps=False, baro_offset=0.0)
    est = kf.estimate()
    assert est.z_valid and est.v_z_valid
    assert not (est.xy_valid or est.v_xy_valid or est.xy_global or est.z_global or est.dead_reckoning)
    assert math.isnan(est.lat) and math.isnan(est.alt) and math.isnan(est.ref_lat)
    assert est.ref_alt == pytest.approx(ALT0, abs=0.5)  # the first baro sample
    assert np.abs(run.pos_err[:, 2]).max() < 0.5
    assert np.abs(run.vel_err[run.t > 2.0, 2]).max() < 0.3
    assert est.position[2] == pytest.approx(-10.0, abs=0.3)
    assert est.baro_offset == 0.0 and kf.x[X_HGT_OFS] == 0.0  # no offset without a second height sensor


@BOTH_REFS
def test_persistent_baro_step_resets_height_without_gps(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref))
    run = simulate(kf, 25.0, trajectory=hover, use_gps=False, baro_offset=0.0, baro_step=(10.0, 100.0))
    # The 100 m step stays beyond the 5σ gate: z holds on the IMU until the 7 s reset timeout.
    assert np.abs(run.pos_err[run.t < 16.9, 2]).max() < 1.0
    est = kf.estimate()
    assert est.z_reset_counter == 1
    assert est.delta_z == pytest.approx(-100.0, abs=1.5)
    assert est.position[2] == pytest.approx(-100.0, abs=0.5)  # now follows the (stepped) baro
    assert est.alt_reset_counter == 0  # there is no global altitude yet


@BOTH_REFS
def test_unaided_variance_stops_growing_at_p_max(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref))
    level = quat.IDENTITY
    t_us = 1_000_000
    for _ in range(int(600.0 / 0.05)):  # 10 min at DT_MAX_S steps, no aiding at all
        t_us += 50_000
        assert kf.predict(t_us, (0.0, 0.0, -CONSTANTS_ONE_G), level)
    diag = np.diagonal(kf.P)
    assert np.all(np.isfinite(kf.P))
    assert diag[:2].max() > 1e5  # it did run away...
    assert diag.max() < 2e6  # ...and stopped near LPE's P_MAX


def test_vertical_velocity_grows_with_lpe_pn_vz_and_horizontal_with_lpe_pn_v() -> None:
    def velocity_variances(**params: float) -> np.ndarray:
        kf = LocalPositionKF(PositionEstimatorParams(**params))
        t_us = 1_000_000
        for _ in range(21):  # 1 s unaided (the first prediction starts the clock)
            t_us += 50_000
            assert kf.predict(t_us, (0.0, 0.0, -CONSTANTS_ONE_G), quat.IDENTITY)
        return np.diagonal(kf.P)[3:6]

    same = velocity_variances()  # PX4's LPE: one LPE_PN_V for every axis
    quiet = velocity_variances(lpe_pn_vz=0.01)
    assert quiet[:2] == pytest.approx(same[:2])
    assert same[2] - quiet[2] == pytest.approx(0.1**2 - 0.01**2, rel=0.05)  # 1 s of the difference


def test_landed_vehicle_holds_still_instead_of_following_gps_velocity_noise() -> None:
    """LPE's land measurement: while landed the horizontal velocity is zero, so the position averages the
    GPS fixes instead of wandering with the integrated GPS velocity noise (which became the error of home
    at arming). After takeoff the filter follows the GPS velocity again."""

    def wander(run: Run, sel: np.ndarray) -> np.ndarray:
        xy = run.pos_err[sel, :2]
        return np.sum((xy - xy.mean(axis=0)) ** 2, axis=1)

    free, held = [], []
    for seed in range(6):
        on_ground = flight_like(sim_profile_filter(), 20.0, seed=seed, trajectory=hover)
        landed = flight_like(sim_profile_filter(), 20.0, seed=seed, trajectory=hover, landed_until=20.0)
        ground = landed.t >= 5.0
        assert rms(landed.vel_err[ground, :2]) < 0.005 and rms(on_ground.vel_err[ground, :2]) > 0.01
        free.append(wander(on_ground, ground))
        held.append(wander(landed, ground))
    assert math.sqrt(np.mean(held)) < 0.75 * math.sqrt(np.mean(free))
    flown = flight_like(sim_profile_filter(), 14.0, landed_until=5.0)
    assert rms(flown.vel_err[flown.t > 8.0, :2]) < 0.05


def test_land_fusion_needs_the_origin_and_survives_a_delayed_gps_replay() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.1))
    assert not kf.fuse_land()  # no time base
    flight_like(kf, 0.5, gps_latency_s=0.1)
    assert not kf.fuse_land()  # no origin yet: nothing to hold still in
    run = flight_like(kf, 8.0, start_s=0.5, gps_latency_s=0.1, landed_until=8.5)
    assert rms(run.vel_err[run.t > 4.0, :2]) < 0.01


@BOTH_REFS
def test_garbage_inputs_are_rejected_without_corrupting_the_state(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    simulate(kf, 10.0, trajectory=hover)
    x, P = kf.x.copy(), kf.P.copy()
    t = kf.estimate().timestamp_sample
    level = quat.IDENTITY
    g = (0.0, 0.0, -CONSTANTS_ONE_G)
    nan = math.nan

    assert not kf.predict(t + 4000, (nan, 0.0, -9.8), level)
    assert not kf.predict(t + 4000, (0.0, math.inf, -9.8), level)
    assert not kf.predict(t + 4000, (1e6, 0.0, 0.0), level)
    assert not kf.predict(t + 4000, g, (nan, 0.0, 0.0, 0.0))
    assert not kf.predict(t + 4000, g, (0.0, 0.0, 0.0, 0.0))
    assert not kf.predict(t, g, level)  # time does not advance
    assert not kf.predict(t - 4000, g, level)
    assert not kf.fuse_baro(nan)
    assert not kf.fuse_baro(math.inf)
    assert not kf.fuse_baro(1e7)
    assert not kf.fuse_baro(ALT0 + 500.0)  # gated out
    fix = Gps(t, LAT0, LON0, ALT0, 0.0, 0.0, 0.0)
    assert not kf.fuse_gps(replace(fix, latitude_deg=nan))
    assert not kf.fuse_gps(replace(fix, latitude_deg=200.0))
    assert not kf.fuse_gps(replace(fix, altitude_msl_m=math.inf))
    assert not kf.fuse_gps(replace(fix, fix_type=2))
    far_off = replace(fix, latitude_deg=LAT0 + 0.01, altitude_msl_m=ALT0 + 200.0, vel_n_m_s=50.0, vel_d_m_s=20.0)
    assert not kf.fuse_gps(far_off)  # every group gated out
    assert not kf.fuse_gps(replace(fix, timestamp_sample=t - 2_000_000))  # older than the history
    np.testing.assert_array_equal(kf.x, x)
    np.testing.assert_array_equal(kf.P, P)

    # Velocity marked invalid (or NaN) is skipped while the position is still used.
    assert kf.fuse_gps(replace(fix, timestamp_sample=t, vel_n_m_s=nan))
    assert kf.fuse_gps(replace(fix, timestamp_sample=t - 1000, vel_ned_valid=False)) is False  # out of order
    # The filter carries on normally afterwards.
    simulate(kf, 5.0, start_s=10.1, trajectory=hover, seed=3)
    est = kf.estimate()
    assert est.xy_valid and est.z_valid
    assert np.all(np.isfinite(kf.x)) and np.all(np.isfinite(kf.P))


def test_the_parameters_are_the_catalogues_read_by_px4_name() -> None:
    assert LocalPositionKF().params == PositionEstimatorParams()
    assert PositionEstimatorParams().lpe_gps_delay == catalogue.get("LPE_GPS_DELAY").default
    values = {"LPE_GPS_DELAY": 0.3, "EKF2_HGT_REF": HGT_REF_GPS, "MPC_XY_VEL_MAX": 1.0}  # a module's, by PX4 name
    params = PositionEstimatorParams.from_params(values)
    assert (params.lpe_gps_delay, params.ekf2_hgt_ref) == (0.3, HGT_REF_GPS)
    assert {p.name for p in PositionEstimatorParams.PARAMS} >= {"LPE_GPS_DELAY", "EKF2_HGT_REF", "EKF2_ABL_LIM"}


def test_height_reference_is_baro_by_default_and_changes_at_reset_only() -> None:
    kf = LocalPositionKF()
    assert kf.hgt_ref == HGT_REF_BARO
    kf.set_params(PositionEstimatorParams(ekf2_hgt_ref=HGT_REF_GPS))  # PX4: reboot required
    assert kf.hgt_ref == HGT_REF_BARO
    kf.reset()
    assert kf.hgt_ref == HGT_REF_GPS


# ---------------------------------------------------------------------- GPS height reference


def test_gps_reference_gps_alone_initialises_height_and_a_late_baro_brings_its_offset() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=HGT_REF_GPS, lpe_gps_delay=0.0))
    simulate(kf, 10.0, trajectory=hover, use_baro=False)
    est = kf.estimate()
    assert est.z_valid and est.z_global
    assert est.alt == pytest.approx(ALT0, abs=0.5)
    ref_alt = est.ref_alt
    run = simulate(kf, 20.0, start_s=10.0, trajectory=hover)
    est = kf.estimate()
    assert est.ref_alt == ref_alt  # GPS keeps defining z
    assert est.baro_offset == pytest.approx(1.5, abs=0.3)
    assert np.abs(run.pos_err[run.t > 20.0, 2]).max() < 0.3
    assert est.z_reset_counter == 0


def test_gps_reference_persistent_baro_step_moves_the_offset_not_the_height() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=HGT_REF_GPS, lpe_gps_delay=0.0))
    run = simulate(kf, 30.0, trajectory=hover, baro_step=(10.0, 20.0))
    est = kf.estimate()
    assert est.z_reset_counter == 0
    assert np.abs(run.pos_err[:, 2][run.t > 5.0]).max() < 0.4
    assert est.baro_offset == pytest.approx(21.5, abs=0.3)


def test_gps_reference_persistent_gps_altitude_jump_resets_z() -> None:
    kf = sim_profile_filter(ekf2_hgt_ref=HGT_REF_GPS)
    flight_like(kf, 40.0, gps_alt_step=(20.0, 50.0))
    est = kf.estimate()
    assert est.z_reset_counter == 1 and est.alt_reset_counter == 1
    assert est.delta_z == pytest.approx(-50.0, abs=1.0)
    assert est.delta_alt == -est.delta_z
    assert est.alt == pytest.approx(ALT0 + 5.0 + 50.0, abs=0.5)


# ---------------------------------------------------------------------- barometer height reference


def test_baro_reference_holds_the_height_of_a_takeoff_against_gps_altitude_noise() -> None:
    """The flight problem: with GPS as the height reference the frame hangs on GPS altitude (σ 0.5 m)
    and the height change since arming drifts by up to ~0.5 m through a takeoff and hover, depending
    on the noise draw. Referenced to the baro (σ 0.09 m) it stays within 0.15 m for every draw."""
    baro_worst, gps_worst = [], []
    for seed in range(8):
        baro_ref = flight_like(sim_profile_filter(), 40.0, seed=seed)
        gps_ref = flight_like(sim_profile_filter(ekf2_hgt_ref=HGT_REF_GPS), 40.0, seed=seed)
        assert baro_ref.z_valid[baro_ref.t > 1.0].all()
        baro_worst.append(np.abs(height_error_since(baro_ref, 4.0)).max())
        gps_worst.append(np.abs(height_error_since(gps_ref, 4.0)).max())
    assert max(baro_worst) < 0.15
    assert max(gps_worst) > 0.4
    assert np.mean(gps_worst) > 2.0 * np.mean(baro_worst)


def test_baro_reference_z_does_not_see_a_constant_gps_altitude_bias() -> None:
    """Hand-worked: with a +3 m GPS altitude bias from the start, every GPS altitude innovation
    z − offset is unchanged once the offset has taken the bias, so z (and every other state) is the
    same as without the bias, and the bias ends in the offset and in the global altitude."""
    unbiased_kf = sim_profile_filter()
    biased_kf = sim_profile_filter()
    unbiased = flight_like(unbiased_kf, 30.0)
    biased = flight_like(biased_kf, 30.0, gps_alt_step=(-math.inf, 3.0))
    np.testing.assert_allclose(biased.z, unbiased.z, rtol=0.0, atol=1e-9)
    assert biased_kf.x[X_HGT_OFS] - unbiased_kf.x[X_HGT_OFS] == pytest.approx(3.0, abs=1e-9)
    assert biased_kf.x[X_HGT_OFS] == pytest.approx(3.0, abs=0.2)
    global_alt = biased.t > 2.0
    np.testing.assert_allclose(biased.alt[global_alt], unbiased.alt[global_alt] + 3.0, rtol=0.0, atol=1e-9)
    est = biased_kf.estimate()
    assert est.alt == pytest.approx(ALT0 + 5.0 + 3.0, abs=0.2)
    assert est.baro_offset == pytest.approx(-3.0, abs=0.2)


@BOTH_REFS
def test_gps_altitude_jump_inside_the_gate_moves_the_offset_with_the_baro_reference(hgt_ref: int) -> None:
    """A +3 m GPS altitude jump (inside the gate) against the same flight without it: with the baro
    reference it goes to the offset, so alt follows GPS altitude and z moves by millimetres; with
    the GPS reference z itself is pulled toward it."""
    kf = sim_profile_filter(ekf2_hgt_ref=hgt_ref)
    jumped = flight_like(kf, 60.0, gps_alt_step=(20.0, 3.0))
    steady = flight_like(sim_profile_filter(ekf2_hgt_ref=hgt_ref), 60.0)
    est = kf.estimate()
    assert est.z_reset_counter == 0 and est.alt_reset_counter == 0
    z_moved = np.abs(jumped.z - steady.z).max()
    if hgt_ref == HGT_REF_BARO:
        assert z_moved < 0.02
        assert np.abs(height_error_since(jumped, 4.0)).max() < 0.15
        assert kf.x[X_HGT_OFS] == pytest.approx(3.0, abs=0.2)
        assert est.alt == pytest.approx(ALT0 + 5.0 + 3.0, abs=0.2)
    else:
        assert z_moved > 1.0


def test_baro_reference_persistent_baro_step_resets_z_and_keeps_the_global_altitude() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.0))
    run = simulate(kf, 30.0, trajectory=hover, baro_step=(10.0, 20.0))
    est = kf.estimate()
    # Rejected for 7 s, then z follows its reference, the baro; the GPS offset moves with z.
    assert est.z_reset_counter == 1
    assert est.delta_z == pytest.approx(-20.0, abs=0.5)
    assert est.position[2] == pytest.approx(-20.0, abs=0.5)
    assert est.alt_reset_counter == 0
    assert np.abs(run.alt[run.t > 3.0] - ALT0).max() < 0.4
    assert est.baro_offset == pytest.approx(21.5, abs=0.3)


def test_baro_reference_persistent_gps_altitude_jump_resets_the_offset_not_z() -> None:
    kf = sim_profile_filter()
    run = flight_like(kf, 40.0, gps_alt_step=(20.0, 50.0))
    est = kf.estimate()
    assert est.z_reset_counter == 0
    assert np.abs(height_error_since(run, 4.0)).max() < 0.15
    assert est.alt_reset_counter == 1
    assert est.delta_alt == pytest.approx(50.0, abs=1.0)
    assert kf.x[X_HGT_OFS] == pytest.approx(50.0, abs=0.5)
    assert est.alt == pytest.approx(ALT0 + 5.0 + 50.0, abs=0.5)
    # Before the 7 s timeout the jump is rejected: alt stays on the true altitude.
    rejected = (run.t > 20.5) & (run.t < 26.9)
    assert np.abs(run.alt[rejected] - (ALT0 - run.true_down[rejected])).max() < 0.3


def test_baro_reference_gps_loss_keeps_z_on_the_baro() -> None:
    kf = sim_profile_filter()
    run = flight_like(kf, 20.0)
    var_offset_before = kf.P[X_HGT_OFS, X_HGT_OFS]
    outage = flight_like(kf, 10.0, start_s=20.0, seed=1, use_gps=False)
    var_offset_lost = kf.P[X_HGT_OFS, X_HGT_OFS]
    after = flight_like(kf, 10.0, start_s=30.0, seed=2)
    assert outage.dead_reckoning[outage.t > 21.2].all()
    assert outage.z_valid.all()
    z = np.concatenate((run.z, outage.z, after.z))
    true_down = np.concatenate((run.true_down, outage.true_down, after.true_down))
    t = np.concatenate((run.t, outage.t, after.t))
    arm = int(np.searchsorted(t, 4.0))
    assert np.abs((z[arm:] - z[arm]) - (true_down[arm:] - true_down[arm])).max() < 0.15
    # Without GPS the offset is a random walk only: its variance grows by LPE_PN_GPS_Z²·10 s.
    grown = var_offset_lost - var_offset_before
    assert grown == pytest.approx(kf.params.lpe_pn_gps_z**2 * 10.0, rel=0.01)
    assert kf.P[X_HGT_OFS, X_HGT_OFS] < var_offset_lost
    est = kf.estimate()
    assert est.z_reset_counter == 0 and est.alt_reset_counter == 0 and not est.dead_reckoning


def test_baro_reference_late_baro_takes_over_from_gps_without_a_height_jump() -> None:
    kf = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.0))
    simulate(kf, 10.0, trajectory=hover, use_baro=False)
    est = kf.estimate()
    assert est.z_valid and est.z_global  # GPS stood in as the height reference
    assert est.alt == pytest.approx(ALT0, abs=0.5)
    z_gps = est.position[2]
    run = simulate(kf, 20.0, start_s=10.0, trajectory=hover)
    assert abs(run.z[0] - z_gps) < 0.01  # z is continuous at the switch
    est = kf.estimate()
    assert est.z_reset_counter == 0 and est.alt_reset_counter == 0
    assert est.baro_offset == pytest.approx(1.5, abs=0.3)
    assert est.alt == pytest.approx(ALT0, abs=0.3)
    # The absolute altitude starts from the GPS-only estimate (0.5 m noise per fix) and only improves.
    alt_err = np.abs(run.pos_err[run.t > 20.0, 2])
    assert alt_err.max() < 0.4 and alt_err[-1] < 0.2


def textbook_gps_update(
    x: np.ndarray, P: np.ndarray, y: np.ndarray, var: list[float], rows: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Kalman update with GPS rows x, y, z − offset, vx, vy, vz (baro reference), restricted to ``rows``."""
    H = np.zeros((6, 10))
    H[range(6), range(6)] = 1.0
    H[2, X_HGT_OFS] = -1.0
    H, R, y = H[list(rows)], np.diag(var)[np.ix_(rows, rows)], y[list(rows)]
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return x + K @ (y - H @ x), P - K @ H @ P


def baro_reference_filter_and_fix(alt_above_prediction: float) -> tuple[LocalPositionKF, Gps, np.ndarray, list[float]]:
    """A baro-referenced filter after 10 s of hover, and a fix at its current time that agrees with
    its position and velocity and reads ``alt_above_prediction`` above its GPS altitude prediction.
    epv is 0.05 m, so that the offset's share of the altitude innovation variance matters."""
    kf = sim_profile_filter(lpe_gps_z=0.01)
    simulate(kf, 10.0, trajectory=hover)
    est = kf.estimate()
    x = kf.x
    local = MapProjection(est.ref_lat, est.ref_lon)
    lat, lon = local.reproject(x[0], x[1])
    baro_ref_alt = est.ref_alt - x[X_HGT_OFS]
    alt = baro_ref_alt - x[X_Z] + x[X_HGT_OFS] + alt_above_prediction
    fix = Gps(est.timestamp_sample, lat, lon, alt, x[3], x[4], x[5], eph=0.9, epv=0.05)
    y = np.array((*local.project(lat, lon), baro_ref_alt - alt, x[3], x[4], x[5]))
    p = kf.params
    var = [max(p.lpe_gps_xy, 0.9) ** 2] * 2 + [0.05**2] + [p.lpe_gps_vxy**2] * 2 + [p.lpe_gps_vz**2]
    return kf, fix, y, var


def test_baro_reference_gps_update_is_the_kalman_update_with_the_offset_row() -> None:
    """Hand-worked against the textbook update: GPS rows x, y, z − offset, vx, vy, vz."""
    kf, fix, y, var = baro_reference_filter_and_fix(0.07)
    x, P = kf.x.copy(), kf.P.copy()
    assert kf.fuse_gps(fix)
    x_expected, P_expected = textbook_gps_update(x, P, y, var, (0, 1, 2, 3, 4, 5))
    np.testing.assert_allclose(kf.x, x_expected, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(kf.P, P_expected, rtol=0.0, atol=1e-12)
    assert kf.x[X_HGT_OFS] - x[X_HGT_OFS] > 0.0  # the offset took (most of) the innovation


@pytest.mark.parametrize("factor", (0.999, 1.001))
def test_baro_reference_gps_altitude_gate_includes_the_offset_variance(factor: float) -> None:
    """EKF2_GPS_P_GATE on the altitude row: r² ≤ gate²·(P_zz + P_oo − 2·P_zo + R)."""
    kf, _, _, _ = baro_reference_filter_and_fix(0.0)
    P = kf.P
    s_alt = P[X_Z, X_Z] + P[X_HGT_OFS, X_HGT_OFS] - 2.0 * P[X_Z, X_HGT_OFS] + 0.05**2
    assert P[X_HGT_OFS, X_HGT_OFS] - 2.0 * P[X_Z, X_HGT_OFS] > 0.01 * s_alt  # the offset's share matters
    kf, fix, y, var = baro_reference_filter_and_fix(factor * kf.params.ekf2_gps_p_gate * math.sqrt(s_alt))
    x, P = kf.x.copy(), kf.P.copy()
    assert kf.fuse_gps(fix)  # position and velocity agree, so those rows are fused in any case
    assert kf.gps_pos_test_ratio == pytest.approx(factor**2, rel=1e-6)
    rows = (0, 1, 2, 3, 4, 5) if factor < 1.0 else (0, 1, 3, 4, 5)
    x_expected, P_expected = textbook_gps_update(x, P, y, var, rows)
    np.testing.assert_allclose(kf.x, x_expected, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(kf.P, P_expected, rtol=0.0, atol=1e-12)


@BOTH_REFS
def test_a_filter_resumed_from_a_snapshot_carries_on_in_the_same_frame(hgt_ref: int) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    simulate(kf, 20.0, trajectory=hover)
    before = kf.estimate()
    resumed = LocalPositionKF(PositionEstimatorParams(ekf2_hgt_ref=hgt_ref, lpe_gps_delay=0.0))
    resumed.resume(kf.snapshot())
    run = simulate(resumed, 5.0, start_s=20.0, trajectory=hover)
    after = resumed.estimate()
    assert (after.ref_lat, after.ref_lon) == (before.ref_lat, before.ref_lon)
    assert after.xy_valid and after.z_valid and after.xy_reset_counter == 0  # no new origin
    assert run.z_valid.all() and horizontal(run, 20.0).max() < 0.3


@pytest.mark.parametrize(
    "broken",
    [{}, {"x": [0.0] * 3}, {"x": [math.nan] * 10}, {"origin": "here"}, {"hgt_ref": 7}, {"z_initialised": 1}],
)
def test_a_snapshot_that_is_not_one_is_refused_and_changes_nothing(broken: dict) -> None:
    kf = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.0))
    simulate(kf, 5.0, trajectory=hover)
    snap = kf.snapshot()
    other = LocalPositionKF(PositionEstimatorParams(lpe_gps_delay=0.0))
    with pytest.raises(ValueError):
        other.resume({} if not broken else snap | broken)
    assert other.snapshot()["origin"] is None


# ---------------------------------------------------------------------- a plane's airspeed without GPS

PLANE_WIND = np.array((0.0, 5.0, 0.0))  # from the west, as the simulator's SIM_WIND_DIR 270°
PLANE_AIRSPEED, PLANE_RADIUS = 15.0, 80.0


def plane_circle(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Circling at 15 m/s airspeed on an 80 m radius around a centre drifting with the wind."""
    w = PLANE_AIRSPEED / PLANE_RADIUS
    air_p = np.array((PLANE_RADIUS * math.sin(w * t), PLANE_RADIUS * (1.0 - math.cos(w * t)), -40.0))
    air_v = np.array((PLANE_AIRSPEED * math.cos(w * t), PLANE_AIRSPEED * math.sin(w * t), 0.0))
    a = np.array((-PLANE_AIRSPEED * w * math.sin(w * t), PLANE_AIRSPEED * w * math.cos(w * t), 0.0))
    return air_p + PLANE_WIND * t, air_v + PLANE_WIND, a


def plane_attitude(t: float) -> Quat:
    """Nose along the air velocity (no sideslip), 3° angle of attack, banked for the coordinated turn."""
    w = PLANE_AIRSPEED / PLANE_RADIUS
    bank = math.atan(PLANE_AIRSPEED * w / CONSTANTS_ONE_G)
    return quat.from_euler(bank, math.radians(3.0), w * t)


def tilt_error(t: float) -> Quat:
    """An attitude estimate off by up to 0.7° in roll and pitch, slowly varying (gravity tilted into the
    horizontal specific force by 0.1 m/s²: what the accelerometer alone then integrates)."""
    return quat.from_euler(math.radians(0.5 + 0.2 * math.sin(0.1 * t)), math.radians(-0.4 * math.cos(0.07 * t)), 0.0)


def plane_run(seed: int, air: bool, **kwargs) -> Run:
    kf = sim_profile_filter(lpe_airspd_vxy=1.0 if air else 0.0)
    options = {
        "trajectory": plane_circle,
        "attitude_of": plane_attitude,
        "gps_every": GPS_EVERY_10HZ,
        "imu_per_predict": 5,
        "accel_sigma": 0.063,
        "accel_bias_body": (0.08, -0.06, 0.05),
        "attitude_error": tilt_error,
        "gps_outage": (30.0, 60.0),
        "air_data": AirData(PLANE_WIND, wind_error=(0.2, -0.2)),
        "seed": seed,
    } | kwargs
    return simulate(kf, 70.0, **options)


def test_a_plane_without_gps_dead_reckons_on_airspeed_and_wind() -> None:
    """30 s without GPS in a turn, in 5 m/s wind known to 0.3 m/s and with an attitude estimate 0.7° off: the
    velocity error stays about that of the wind estimate instead of growing with the tilted specific force."""
    for seed in range(3):
        inertial, aided = plane_run(seed, air=False), plane_run(seed, air=True)
        outage = (aided.t >= 31.0) & (aided.t < 60.0)
        assert aided.dead_reckoning[outage].all() and inertial.dead_reckoning[outage].all()
        aided_v = np.hypot(aided.vel_err[outage, 0], aided.vel_err[outage, 1])
        inertial_v = np.hypot(inertial.vel_err[outage, 0], inertial.vel_err[outage, 1])
        assert aided_v.max() < 0.7 and inertial_v.max() > 0.9
        # The wind estimate's 0.28 m/s error, over 30 s, against the tilted gravity integrated twice.
        assert horizontal(aided, 59.0, 60.0).max() < 10.0 and horizontal(inertial, 59.0, 60.0).max() > 12.0
        # GPS back: the estimate rejoins it.
        assert horizontal(aided, 65.0).max() < 1.0 and not aided.dead_reckoning[aided.t > 62.0].any()


def test_airspeed_is_fused_only_without_gps_and_never_when_it_is_garbage() -> None:
    kf = sim_profile_filter()
    wind, var = (0.0, 5.0), (0.04, 0.04)
    assert not kf.fuse_airspeed(15.0, plane_attitude(0.0), wind, var)  # no time base
    simulate(kf, 10.0, trajectory=plane_circle, attitude_of=plane_attitude, gps_every=GPS_EVERY_10HZ)
    assert not kf.fuse_airspeed(15.0, plane_attitude(10.0), wind, var)  # GPS is fused: it is far better
    simulate(
        kf, 3.0, start_s=10.0, trajectory=plane_circle, attitude_of=plane_attitude, gps_outage=(10.0, 20.0)
    )
    q = plane_attitude(13.0)
    x, P = kf.x.copy(), kf.P.copy()
    for args in (
        (math.nan, q, wind, var),
        (15.0, (math.nan, 0.0, 0.0, 0.0), wind, var),
        (15.0, (0.0, 0.0, 0.0, 0.0), wind, var),
        (15.0, q, (math.inf, 0.0), var),
        (15.0, q, wind, (-1.0, 0.04)),
        (-3.0, q, wind, var),
        (1e9, q, wind, var),
        (15.0, quat.from_euler(0.0, 0.0, math.pi), wind, var),  # 30 m/s off: outside the gate
    ):
        assert not kf.fuse_airspeed(*args), args
    assert np.array_equal(kf.x, x) and np.array_equal(kf.P, P)
    _, v, _ = plane_circle(13.0)
    air = quat.rotate_inv(q, tuple(v - PLANE_WIND))
    assert kf.fuse_airspeed(math.sqrt(sum(c * c for c in air)), q, wind, var)
    off = sim_profile_filter(lpe_airspd_vxy=0.0)
    simulate(off, 13.0, trajectory=plane_circle, attitude_of=plane_attitude, gps_outage=(10.0, 20.0))
    assert not off.fuse_airspeed(15.0, q, wind, var)


def test_airspeed_fusion_survives_a_delayed_gps_replay() -> None:
    """A GPS fix that arrives late rolls the filter back past airspeed fusions, which are replayed."""
    run = plane_run(4, air=True, gps_latency_s=0.2, gps_outage=(30.0, 45.0))
    assert horizontal(run, 50.0).max() < 1.0
