"""Seeded sensor models of the simulator: IMU, magnetometer, barometer and GPS.

Each model draws from its own ``random.Random`` stream (the simulator derives one per sensor from
the run seed and the sensor name), so adding or re-rating one sensor never shifts another's noise.
Every sample carries ``time_us``, the simulated time of the truth it measures (PX4's
``timestamp_sample``).

Default figures and their sources:

* IMU — the RotorS ``gazebo_imu_plugin`` model with its ADIS16448 figures: gyro noise density
  3.3937e-4 rad/s/√Hz, gyro bias random walk 3.8785e-5 rad/s²/√Hz with correlation time 1000 s,
  accel noise density 4.0e-3 m/s²/√Hz, accel bias correlation time 300 s. At 250 Hz that is a
  white σ of 5.4e-3 rad/s and 0.063 m/s². Two departures, both so that an accelerometer-levelled
  attitude filter stays well under 1°:
  - accel bias random walk 2.0e-4 m/s³/√Hz instead of RotorS' 6.0e-3: with τ = 300 s this gives
    the ADIS16448 datasheet's 0.25 mg in-run bias stability as the stationary bias σ. RotorS'
    figure implies 7.5 mg, 30× the datasheet, and alone tilts such a filter by ~0.6° RMS.
  - turn-on biases (ADIS16448: 0.5 °/s, 20 mg) default to 0, as an autopilot calibrates them out
    on the ground; set them to exercise bias estimation.
  With the defaults a complementary filter with PX4 attitude_estimator_q gains holds attitude to
  ~0.1° RMS at hover. Temperature 15 °C as PX4 SIH's IMU.
* Magnetometer — Earth field at the home point from declination, inclination and strength (WMM
  figures for Zürich, the SIH home: 3.2°, 63.5°, 0.483 G), rotated into body; noise σ
  (0.02, 0.02, 0.03) G and offsets SIM_MAG_OFFSET_X/Y/Z as PX4 ``sensor_mag_sim``.
* Barometer — ISA troposphere pressure at the altitude AMSL, 1 Pa RMS noise as PX4
  ``sensor_baro_sim``, offsets SIM_BARO_OFF_P (Pa) and SIM_BARO_OFF_T (°C).
* GPS — PX4 ``sensor_gps_sim`` figures: position σ 0.2 m horizontal and 0.5 m vertical, velocity σ
  (0.06, 0.077, 0.158) m/s, 10 satellites (SIM_GPS_USED), fix 3, eph 0.9 m, epv 1.78 m, hdop 0.7,
  vdop 1.1, speed variance 0.4 m/s; optional slowly varying (Gauss–Markov) position error and a
  measurement delay. Switched off, it reports no fix (fix 0, no satellites, eph/epv 100 m) with NaN
  position and velocity.
"""

from __future__ import annotations

import math
import random
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

from stack.mathlib.atmosphere import isa_pressure_pa, isa_temperature_k
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import Quat, rotate_inv
from stack.mathlib.vector import ZERO3, Vec3

KELVIN_OFFSET = 273.15


class ImuSample(NamedTuple):
    time_us: int
    gyro: Vec3  # rad/s, body FRD
    accel: Vec3  # m/s², specific force in body FRD
    temperature: float  # °C


class MagSample(NamedTuple):
    time_us: int
    field: Vec3  # Gauss, body FRD


class BaroSample(NamedTuple):
    time_us: int
    pressure_pa: float
    temperature: float  # °C


class GpsSample(NamedTuple):
    time_us: int  # time of the measurement (it is published ``delay`` later)
    lat: float  # deg
    lon: float  # deg
    alt_msl: float  # m
    vel_ned: Vec3  # m/s
    eph: float  # m
    epv: float  # m
    hdop: float
    vdop: float
    s_variance_m_s: float
    fix_type: int  # 3 = 3-D fix, 0 = none
    satellites: int


@dataclass(frozen=True, slots=True)
class ImuParams:
    """IMU noise (RotorS ``gazebo_imu_plugin`` SDF names in brackets; ADIS16448 defaults, see the module docstring).

    gyro_noise_density rad/s/√Hz [gyroscopeNoiseDensity]; gyro_random_walk rad/s²/√Hz
    [gyroscopeRandomWalk]; gyro_bias_correlation_time s [gyroscopeBiasCorrelationTime];
    gyro_turn_on_bias_sigma rad/s [gyroscopeTurnOnBiasSigma]; the accel_* figures likewise in m/s²,
    m/s³/√Hz, s and m/s². temperature °C.
    """

    gyro_noise_density: float = 3.3937e-4
    gyro_random_walk: float = 3.8785e-5
    gyro_bias_correlation_time: float = 1000.0
    gyro_turn_on_bias_sigma: float = 0.0
    accel_noise_density: float = 4.0e-3
    accel_random_walk: float = 2.0e-4
    accel_bias_correlation_time: float = 300.0
    accel_turn_on_bias_sigma: float = 0.0
    temperature: float = 15.0

    def __post_init__(self) -> None:
        for name in (
            "gyro_noise_density",
            "gyro_random_walk",
            "gyro_turn_on_bias_sigma",
            "accel_noise_density",
            "accel_random_walk",
            "accel_turn_on_bias_sigma",
        ):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"ImuParams.{name} must be >= 0")
        if not (self.gyro_bias_correlation_time > 0.0 and self.accel_bias_correlation_time > 0.0):
            raise ValueError("ImuParams bias correlation times must be > 0")


@dataclass(frozen=True, slots=True)
class MagParams:
    """Magnetometer: Earth field at home (declination/inclination deg, strength Gauss), noise σ per axis
    (Gauss) and offsets (SIM_MAG_OFFSET_X/Y/Z, Gauss)."""

    declination_deg: float = 3.2
    inclination_deg: float = 63.5
    strength_gauss: float = 0.483
    noise: Vec3 = (0.02, 0.02, 0.03)
    offset: Vec3 = ZERO3

    def __post_init__(self) -> None:
        if not self.strength_gauss > 0.0 or not all(s >= 0.0 for s in self.noise):
            raise ValueError("MagParams: strength must be > 0 and noise >= 0")


@dataclass(frozen=True, slots=True)
class BaroParams:
    """Barometer: white pressure noise σ (Pa), offsets SIM_BARO_OFF_P (Pa) and SIM_BARO_OFF_T (°C)."""

    noise_pa: float = 1.0
    offset_pa: float = 0.0
    offset_temperature: float = 0.0

    def __post_init__(self) -> None:
        if not self.noise_pa >= 0.0:
            raise ValueError("BaroParams.noise_pa must be >= 0")


@dataclass(frozen=True, slots=True)
class GpsParams:
    """GPS receiver.

    noise_horizontal / noise_vertical: white position noise σ (m); velocity_noise: σ NED (m/s);
    drift_horizontal / drift_vertical: σ (m) of a slowly varying Gauss–Markov position error with
    correlation time drift_time_constant (s); delay: measurement-to-publication latency (s);
    satellites (SIM_GPS_USED), eph, epv (m), hdop, vdop, s_variance_m_s: reported quality figures;
    enabled: initial on/off (off = no fix).
    """

    noise_horizontal: float = 0.2
    noise_vertical: float = 0.5
    velocity_noise: Vec3 = (0.06, 0.077, 0.158)
    drift_horizontal: float = 0.0
    drift_vertical: float = 0.0
    drift_time_constant: float = 60.0
    delay: float = 0.0
    satellites: int = 10
    eph: float = 0.9
    epv: float = 1.78
    hdop: float = 0.7
    vdop: float = 1.1
    s_variance_m_s: float = 0.4
    enabled: bool = True

    def __post_init__(self) -> None:
        noise = (self.noise_horizontal, self.noise_vertical, *self.velocity_noise)
        if not all(s >= 0.0 for s in noise):
            raise ValueError("GpsParams: noise figures must be >= 0")
        if not (self.drift_horizontal >= 0.0 and self.drift_vertical >= 0.0 and self.drift_time_constant > 0.0):
            raise ValueError("GpsParams: drift figures must be >= 0 and drift_time_constant > 0")
        if not self.delay >= 0.0:
            raise ValueError("GpsParams.delay must be >= 0")


class _GaussMarkov3:
    """Three independent first-order Gauss–Markov processes with stationary σ per axis, exact for a fixed dt."""

    __slots__ = ("_phi", "_scale", "state")

    def __init__(self, sigma: Vec3, time_constant: float, dt: float, initial: Vec3 = ZERO3) -> None:
        self._phi = math.exp(-dt / time_constant)
        root = math.sqrt(1.0 - self._phi * self._phi)
        self._scale = (sigma[0] * root, sigma[1] * root, sigma[2] * root)
        self.state = initial

    def step(self, gauss: Callable[[float, float], float]) -> Vec3:
        phi = self._phi
        sx, sy, sz = self._scale
        x, y, z = self.state
        self.state = (
            phi * x + sx * gauss(0.0, 1.0),
            phi * y + sy * gauss(0.0, 1.0),
            phi * z + sz * gauss(0.0, 1.0),
        )
        return self.state


class ImuModel:
    """Gyro and accelerometer: truth + Gauss–Markov bias + turn-on bias + white noise (RotorS IMU model).

    The white-noise σ of a sample is density/√dt and the bias is a Gauss–Markov process with the given
    random walk and correlation time, both discretised for the sample period 1/``rate_hz``.
    """

    __slots__ = (
        "_accel_bias",
        "_accel_sigma",
        "_accel_turn_on",
        "_gauss",
        "_gyro_bias",
        "_gyro_sigma",
        "_gyro_turn_on",
        "params",
    )

    def __init__(self, params: ImuParams, rate_hz: float, rng: random.Random) -> None:
        if not rate_hz > 0.0:
            raise ValueError("rate_hz must be > 0")
        self.params = params
        dt = 1.0 / rate_hz
        gauss = rng.gauss
        self._gauss = gauss
        self._gyro_sigma = params.gyro_noise_density / math.sqrt(dt)
        self._accel_sigma = params.accel_noise_density / math.sqrt(dt)
        # Stationary bias σ of a Gauss–Markov process driven by a random walk q: q·√(τ/2).
        tau_g, tau_a = params.gyro_bias_correlation_time, params.accel_bias_correlation_time
        gyro_bias_sigma = params.gyro_random_walk * math.sqrt(0.5 * tau_g)
        accel_bias_sigma = params.accel_random_walk * math.sqrt(0.5 * tau_a)
        self._gyro_bias = _GaussMarkov3((gyro_bias_sigma,) * 3, tau_g, dt)
        self._accel_bias = _GaussMarkov3((accel_bias_sigma,) * 3, tau_a, dt)
        sg, sa = params.gyro_turn_on_bias_sigma, params.accel_turn_on_bias_sigma
        self._gyro_turn_on = (sg * gauss(0.0, 1.0), sg * gauss(0.0, 1.0), sg * gauss(0.0, 1.0))
        self._accel_turn_on = (sa * gauss(0.0, 1.0), sa * gauss(0.0, 1.0), sa * gauss(0.0, 1.0))

    @property
    def gyro_bias(self) -> Vec3:
        """Total gyro bias now (rad/s): Gauss–Markov part + turn-on part."""
        b, t = self._gyro_bias.state, self._gyro_turn_on
        return (b[0] + t[0], b[1] + t[1], b[2] + t[2])

    @property
    def accel_bias(self) -> Vec3:
        """Total accelerometer bias now (m/s²)."""
        b, t = self._accel_bias.state, self._accel_turn_on
        return (b[0] + t[0], b[1] + t[1], b[2] + t[2])

    def sample(self, time_us: int, angular_velocity: Vec3, specific_force: Vec3) -> ImuSample:
        """Measure the true body rates (rad/s) and specific force (m/s², body FRD)."""
        gauss = self._gauss
        bgx, bgy, bgz = self._gyro_bias.step(gauss)
        bax, bay, baz = self._accel_bias.step(gauss)
        tgx, tgy, tgz = self._gyro_turn_on
        tax, tay, taz = self._accel_turn_on
        sg = self._gyro_sigma
        sa = self._accel_sigma
        wx, wy, wz = angular_velocity
        fx, fy, fz = specific_force
        return ImuSample(
            time_us,
            (
                wx + bgx + tgx + sg * gauss(0.0, 1.0),
                wy + bgy + tgy + sg * gauss(0.0, 1.0),
                wz + bgz + tgz + sg * gauss(0.0, 1.0),
            ),
            (
                fx + bax + tax + sa * gauss(0.0, 1.0),
                fy + bay + tay + sa * gauss(0.0, 1.0),
                fz + baz + taz + sa * gauss(0.0, 1.0),
            ),
            self.params.temperature,
        )


class MagnetometerModel:
    """Earth field at home rotated into body, plus offset and white noise (PX4 ``sensor_mag_sim``)."""

    __slots__ = ("_gauss", "earth_field_ned", "params")

    def __init__(self, params: MagParams, rng: random.Random) -> None:
        self.params = params
        self._gauss = rng.gauss
        declination = math.radians(params.declination_deg)
        inclination = math.radians(params.inclination_deg)
        horizontal = params.strength_gauss * math.cos(inclination)
        self.earth_field_ned: Vec3 = (
            horizontal * math.cos(declination),
            horizontal * math.sin(declination),
            params.strength_gauss * math.sin(inclination),
        )

    def sample(self, time_us: int, attitude: Quat) -> MagSample:
        """Measure the field in body FRD (Gauss) for the true attitude (body → NED)."""
        gauss = self._gauss
        bx, by, bz = rotate_inv(attitude, self.earth_field_ned)
        ox, oy, oz = self.params.offset
        nx, ny, nz = self.params.noise
        return MagSample(
            time_us,
            (bx + ox + nx * gauss(0.0, 1.0), by + oy + ny * gauss(0.0, 1.0), bz + oz + nz * gauss(0.0, 1.0)),
        )


class BarometerModel:
    """ISA static pressure and temperature at the true altitude AMSL, plus offsets and noise."""

    __slots__ = ("_gauss", "params")

    def __init__(self, params: BaroParams, rng: random.Random) -> None:
        self.params = params
        self._gauss = rng.gauss

    def sample(self, time_us: int, altitude_msl: float) -> BaroSample:
        p = self.params
        pressure = isa_pressure_pa(altitude_msl) + p.offset_pa + p.noise_pa * self._gauss(0.0, 1.0)
        temperature = isa_temperature_k(altitude_msl) - KELVIN_OFFSET + p.offset_temperature
        return BaroSample(time_us, pressure, temperature)


class GpsModel:
    """GPS receiver: noisy geodetic position and NED velocity, published ``delay`` after the measurement.

    :meth:`measure` takes a measurement of the truth now; :meth:`pop_due` hands out the measurements
    whose publication time has come, oldest first, each stamped with its measurement time.
    """

    __slots__ = (
        "_drift",
        "_enabled",
        "_gauss",
        "_has_drift",
        "_home_alt",
        "_pending",
        "_projection",
        "delay_us",
        "params",
    )

    def __init__(
        self, params: GpsParams, rate_hz: float, projection: MapProjection, home_alt_msl: float, rng: random.Random
    ) -> None:
        if not rate_hz > 0.0:
            raise ValueError("rate_hz must be > 0")
        self.params = params
        self._projection = projection
        self._home_alt = home_alt_msl
        self._gauss = rng.gauss
        self._enabled = params.enabled
        self.delay_us = round(params.delay * 1e6)
        self._pending: deque[tuple[int, GpsSample]] = deque()
        sh, sv = params.drift_horizontal, params.drift_vertical
        self._has_drift = sh > 0.0 or sv > 0.0
        initial = ZERO3
        if self._has_drift:
            initial = (sh * rng.gauss(0.0, 1.0), sh * rng.gauss(0.0, 1.0), sv * rng.gauss(0.0, 1.0))
        self._drift = _GaussMarkov3((sh, sh, sv), params.drift_time_constant, 1.0 / rate_hz, initial)

    @property
    def enabled(self) -> bool:
        return self._enabled

    def set_enabled(self, enabled: bool) -> None:
        """Switch the receiver on or off; measurements taken while off have no fix."""
        self._enabled = enabled

    def clear(self) -> None:
        """Drop measurements not yet published (after a reset of the plant)."""
        self._pending.clear()

    def measure(self, time_us: int, position_ned: Vec3, velocity_ned: Vec3) -> None:
        """Measure the true position and velocity NED at ``time_us`` (called at ``rate_hz``)."""
        p = self.params
        gauss = self._gauss
        publish_us = time_us + self.delay_us
        if not self._enabled:
            nan = math.nan
            self._pending.append(
                (publish_us, GpsSample(time_us, nan, nan, nan, (nan, nan, nan), 100.0, 100.0, 99.99, 99.99, nan, 0, 0))
            )
            return
        if self._has_drift:
            dn, de, dd = self._drift.step(gauss)
        else:
            dn = de = dd = 0.0
        nh, nv = p.noise_horizontal, p.noise_vertical
        north = position_ned[0] + dn + nh * gauss(0.0, 1.0)
        east = position_ned[1] + de + nh * gauss(0.0, 1.0)
        down = position_ned[2] + dd + nv * gauss(0.0, 1.0)
        lat, lon = self._projection.reproject(north, east)
        svn, sve, svd = p.velocity_noise
        velocity = (
            velocity_ned[0] + svn * gauss(0.0, 1.0),
            velocity_ned[1] + sve * gauss(0.0, 1.0),
            velocity_ned[2] + svd * gauss(0.0, 1.0),
        )
        self._pending.append(
            (
                publish_us,
                GpsSample(
                    time_us,
                    lat,
                    lon,
                    self._home_alt - down,
                    velocity,
                    p.eph,
                    p.epv,
                    p.hdop,
                    p.vdop,
                    p.s_variance_m_s,
                    3,
                    p.satellites,
                ),
            )
        )

    def pop_due(self, time_us: int) -> GpsSample | None:
        """The oldest measurement whose publication time is at or before ``time_us``, or None."""
        pending = self._pending
        if pending and pending[0][0] <= time_us:
            return pending.popleft()[1]
        return None
