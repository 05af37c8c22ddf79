"""LocalPositionKF on synthetic IMU/GPS/baro data: convergence, tracking, delay, outage, resets, garbage."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import pytest

from stack.estimator.position_kf import LocalPositionKF
from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G

LAT0, LON0, ALT0 = 47.397742, 8.545594, 488.0
IMU_DT_US = 4000  # 250 Hz
GPS_EVERY = 31  # IMU steps between GPS fixes (~8 Hz)
BARO_EVERY = 12  # ~20 Hz
T0_US = 5_000_000

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


def attitude(t: float) -> Quat:
    """A slowly yawing, slightly tilted vehicle (the filter must use q, whatever it is)."""
    return quat.from_euler(0.08 * math.sin(0.7 * t), -0.05 * math.cos(0.5 * t), 0.3 * t)


@dataclass
class Run:
    """Per-IMU-step ground truth and estimates, in the filter's own local frame."""

    t: np.ndarray
    pos_err: np.ndarray  # (n, 3)
    vel_err: np.ndarray
    eph: np.ndarray
    xy_valid: np.ndarray
    dead_reckoning: np.ndarray
    z_valid: np.ndarray


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
    use_gps: bool = True,
    use_baro: bool = True,
    baro_offset: float = 1.5,
    baro_step: tuple[float, float] = (math.inf, 0.0),
) -> Run:
    """Drive ``kf`` along ``trajectory`` with noisy sensors; GPS arrives ``gps_latency_s`` late and is
    stamped with its true sample time (``gps_stamp="sample"``) or its arrival time ("arrival").
    ``start_s`` continues an earlier run of the same filter; the baro jumps by ``baro_step[1]`` metres
    from ``baro_step[0]`` seconds on."""
    rng = np.random.default_rng(seed)
    truth_map = MapProjection(LAT0, LON0)
    pending: list[tuple[int, Gps]] = []
    latency_us = round(gps_latency_s * 1e6)
    rows: list[tuple] = []
    first = round(start_s * 1e6 / IMU_DT_US)
    for i in range(first, first + round(seconds * 1e6 / IMU_DT_US)):
        t_us = T0_US + i * IMU_DT_US
        t = (t_us - T0_US) * 1e-6
        p, v, a = trajectory(t)
        q = attitude(t)
        f_body = quat.rotate_inv(q, (a[0], a[1], a[2] - CONSTANTS_ONE_G))
        accel = tuple(f_body[k] + accel_bias_body[k] + rng.normal(0.0, accel_sigma) for k in range(3))
        assert kf.predict(t_us, accel, q)

        if use_baro and i % BARO_EVERY == 0:
            step = baro_step[1] if t >= baro_step[0] else 0.0
            kf.fuse_baro(ALT0 - p[2] + baro_offset + step + rng.normal(0.0, 0.1))
        in_outage = gps_outage is not None and gps_outage[0] <= t < gps_outage[1]
        if use_gps and i % GPS_EVERY == 0 and not in_outage:
            offset = gps_offset_ne if t >= gps_offset_from else (0.0, 0.0)
            north = p[0] + offset[0] + rng.normal(0.0, 0.2)
            east = p[1] + offset[1] + rng.normal(0.0, 0.2)
            lat, lon = truth_map.reproject(north, east)
            vel = v + rng.normal(0.0, (0.06, 0.077, 0.158))
            gps = Gps(t_us, lat, lon, ALT0 - p[2] + rng.normal(0.0, 0.5), *vel)
            pending.append((t_us + latency_us, gps))
        while pending and pending[0][0] <= t_us:
            arrival, gps = pending.pop(0)
            kf.fuse_gps(gps if gps_stamp == "sample" else replace(gps, timestamp_sample=arrival))

        est = kf.estimate()
        if est.xy_global:
            local_map = MapProjection(est.ref_lat, est.ref_lon)
            true_n, true_e = local_map.project(*truth_map.reproject(p[0], p[1]))
            true_z = est.ref_alt - (ALT0 - p[2])
        else:
            true_n, true_e, true_z = math.nan, math.nan, est.ref_alt - (ALT0 - p[2])
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
    )


def rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2)))


def horizontal(run: Run, t_from: float, t_to: float = math.inf) -> np.ndarray:
    sel = (run.t >= t_from) & (run.t < t_to)
    return np.hypot(run.pos_err[sel, 0], run.pos_err[sel, 1])


def test_static_convergence() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
    run = simulate(kf, 30.0, trajectory=hover)
    est = kf.estimate()
    assert est.xy_valid and est.z_valid and est.v_xy_valid and est.v_z_valid
    assert not est.dead_reckoning
    assert est.xy_reset_counter == 1  # the origin was set once
    assert horizontal(run, 20.0).max() < 0.2
    assert np.abs(run.pos_err[run.t > 20.0, 2]).max() < 0.3
    assert rms(run.vel_err[run.t > 20.0]) < 0.05
    assert est.eph < 1.0 and est.epv < 1.0
    # The global position is the truth; the baro offset is learned against GPS altitude.
    north, east = MapProjection(LAT0, LON0).project(est.lat, est.lon)
    assert math.hypot(north, east) < 0.2
    assert est.alt == pytest.approx(ALT0, abs=0.3)
    assert est.baro_offset == pytest.approx(1.5, abs=0.3)


def test_origin_is_set_at_the_first_good_fixes_without_a_height_jump() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
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
    # 10 fixes at ~8 Hz are needed before the origin is set.
    first_global = run.t[~np.isnan(run.pos_err[:, 0])][0]
    assert 2.1 < first_global < 2.4


def test_tracks_a_climbing_circle() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
    run = simulate(kf, 60.0, accel_bias_body=(0.05, -0.05, 0.1))
    assert run.xy_valid[run.t > 5.0].all() and run.z_valid[run.t > 5.0].all()
    assert rms(horizontal(run, 10.0)) < 0.15
    assert rms(run.pos_err[run.t > 10.0, 2]) < 0.2
    assert rms(run.vel_err[run.t > 10.0, :2]) < 0.06
    assert rms(run.vel_err[run.t > 10.0, 2]) < 0.1
    # The body-frame accelerometer bias is learned while the vehicle yaws.
    assert kf.estimate().accel_bias == pytest.approx((0.05, -0.05, 0.1), abs=0.02)


def test_accel_bias_estimate_is_limited_to_ekf2_abl_lim() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0, EKF2_ABL_LIM=0.3)
    simulate(kf, 20.0, trajectory=hover, accel_bias_body=(0.0, 0.0, 1.0))
    assert kf.estimate().accel_bias[2] == 0.3


def test_delayed_gps_is_fused_at_its_sample_time() -> None:
    latency = 0.25  # 0.5 m of travel at 2 m/s
    fused_at_sample = simulate(LocalPositionKF(LPE_GPS_DELAY=0.0), 40.0, gps_latency_s=latency)
    via_parameter = simulate(LocalPositionKF(LPE_GPS_DELAY=latency), 40.0, gps_latency_s=latency, gps_stamp="arrival")
    ignored = simulate(LocalPositionKF(LPE_GPS_DELAY=0.0), 40.0, gps_latency_s=latency, gps_stamp="arrival")
    undelayed = simulate(LocalPositionKF(LPE_GPS_DELAY=0.0), 40.0)
    err_sample = rms(horizontal(fused_at_sample, 10.0))
    err_param = rms(horizontal(via_parameter, 10.0))
    err_ignored = rms(horizontal(ignored, 10.0))
    err_undelayed = rms(horizontal(undelayed, 10.0))
    assert err_sample < 0.15
    assert err_sample < 1.3 * err_undelayed
    assert err_param == pytest.approx(err_sample, rel=1e-9)
    assert err_ignored > 4.0 * err_sample


def test_delayed_fusion_equals_fusing_on_time() -> None:
    """Rolling back, fusing and replaying (IMU and baro) is the exact Kalman answer: it matches a
    filter that received every fix without latency, once both have seen the same fixes."""
    latency_steps = 25  # 0.1 s, shorter than the GPS interval
    seconds = (GPS_EVERY * 40 + latency_steps + 1) * IMU_DT_US * 1e-6  # ends on an arrival
    on_time = LocalPositionKF(LPE_GPS_DELAY=0.0)
    late = LocalPositionKF(LPE_GPS_DELAY=0.0)
    simulate(on_time, seconds)
    simulate(late, seconds, gps_latency_s=latency_steps * IMU_DT_US * 1e-6)
    np.testing.assert_allclose(late.x, on_time.x, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(late.P, on_time.P, rtol=0.0, atol=1e-9)


def test_gps_outage_dead_reckons_then_recovers() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
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
    limit = kf.params["LPE_XY_PUB"]
    assert not run.xy_valid[during].all()
    assert np.array_equal(run.xy_valid[during], eph <= limit)
    # GPS is back: the estimate converges without a reset.
    after = run.t > 33.0
    assert run.xy_valid[after].all() and not run.dead_reckoning[after].any()
    assert horizontal(run, 33.0).max() < 0.25
    assert kf.estimate().xy_reset_counter == 1


def test_persistent_gps_jump_is_rejected_then_reset_to() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
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


def test_baro_only_altitude() -> None:
    def climb(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        # Smooth climb of 10 m between t = 5 s and t = 15 s (cosine velocity profile).
        if t < 5.0:
            return np.zeros(3), np.zeros(3), np.zeros(3)
        if t > 15.0:
            return np.array((0.0, 0.0, -10.0)), np.zeros(3), np.zeros(3)
        s = (t - 5.0) / 10.0
        z = -10.0 * (s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi))
        vz = -1.0 * (1.0 - math.cos(2.0 * math.pi * s))
        az = -0.2 * math.pi * math.sin(2.0 * math.pi * s)
        return np.array((0.0, 0.0, z)), np.array((0.0, 0.0, vz)), np.array((0.0, 0.0, az))

    kf = LocalPositionKF()
    run = simulate(kf, 25.0, trajectory=climb, use_gps=False, baro_offset=0.0)
    est = kf.estimate()
    assert est.z_valid and est.v_z_valid
    assert not (est.xy_valid or est.v_xy_valid or est.xy_global or est.z_global or est.dead_reckoning)
    assert math.isnan(est.lat) and math.isnan(est.ref_lat)
    assert est.ref_alt == pytest.approx(ALT0, abs=0.5)  # the first baro sample
    assert np.abs(run.pos_err[:, 2]).max() < 0.5
    assert np.abs(run.vel_err[run.t > 2.0, 2]).max() < 0.3
    assert est.position[2] == pytest.approx(-10.0, abs=0.3)
    assert est.baro_offset == 0.0  # frozen until GPS altitude defines the reference


def test_gps_alone_initialises_height_and_a_late_baro_brings_its_offset() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
    simulate(kf, 10.0, trajectory=hover, use_baro=False)
    est = kf.estimate()
    assert est.z_valid and est.z_global
    assert est.alt == pytest.approx(ALT0, abs=0.5)
    run = simulate(kf, 20.0, start_s=10.0, trajectory=hover)
    est = kf.estimate()
    assert est.baro_offset == pytest.approx(1.5, abs=0.3)
    assert np.abs(run.pos_err[run.t > 20.0, 2]).max() < 0.3
    assert est.z_reset_counter == 0


def test_persistent_baro_step_resets_height_without_gps() -> None:
    kf = LocalPositionKF()
    run = simulate(kf, 25.0, trajectory=hover, use_gps=False, baro_offset=0.0, baro_step=(10.0, 100.0))
    # The 100 m step stays beyond the 5σ gate: z holds on the IMU until the 7 s reset timeout.
    assert np.abs(run.pos_err[run.t < 16.9, 2]).max() < 1.0
    est = kf.estimate()
    assert est.z_reset_counter == 1
    assert est.delta_z == pytest.approx(-100.0, abs=1.5)
    assert est.position[2] == pytest.approx(-100.0, abs=0.5)  # now follows the (stepped) baro


def test_persistent_baro_step_with_gps_moves_the_offset_not_the_height() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
    run = simulate(kf, 30.0, trajectory=hover, baro_step=(10.0, 20.0))
    est = kf.estimate()
    assert est.z_reset_counter == 0
    assert np.abs(run.pos_err[:, 2][run.t > 5.0]).max() < 0.4
    assert est.baro_offset == pytest.approx(21.5, abs=0.3)


def test_unaided_variance_stops_growing_at_p_max() -> None:
    kf = LocalPositionKF()
    level = quat.IDENTITY
    t_us = 1_000_000
    for _ in range(int(600.0 / 0.05)):  # 10 min at DT_MAX_S steps, no aiding at all
        t_us += 50_000
        assert kf.predict(t_us, (0.0, 0.0, -CONSTANTS_ONE_G), level)
    diag = np.diagonal(kf.P)
    assert np.all(np.isfinite(kf.P))
    assert diag[:2].max() > 1e5  # it did run away...
    assert diag.max() < 2e6  # ...and stopped near LPE's P_MAX


def test_garbage_inputs_are_rejected_without_corrupting_the_state() -> None:
    kf = LocalPositionKF(LPE_GPS_DELAY=0.0)
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


def test_set_params_validates_names_and_ranges() -> None:
    kf = LocalPositionKF()
    kf.set_params(LPE_GPS_DELAY=5.0, LPE_BAR_Z=0.0)
    assert kf.params["LPE_GPS_DELAY"] == 0.4 and kf.params["LPE_BAR_Z"] == 0.01
    with pytest.raises(KeyError):
        kf.set_params(LPE_NOT_A_PARAM=1.0)
