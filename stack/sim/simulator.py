"""The simulator core: plant, wind and sensors stepped on an exact integer-microsecond clock.

:class:`Simulator` is what the simulator module wraps. One :meth:`Simulator.advance` moves time on
by exactly one IMU period (an integer number of physics steps with the motor commands and the wind
held) and returns the sensor samples that fell due at the new time: always an IMU sample, and a
magnetometer, barometer or GPS sample when their own period has elapsed; for a fixed-wing, an
airspeed sample too (PX4 SIH publishes it at 20 Hz). This mirrors PX4 SIH's
lockstep loop, where each simulator step publishes the IMU and the slower sensors at their rates.

The accelerometer reads the mean specific force over the IMU period (the velocity change over the
period, less gravity, in the body frame at the sample time), as PX4's delta-velocity integration
delivers it; the gyro reads the body rates at the sample time.

The plant is :class:`MulticopterPhysics` or, for a fixed-wing model, :class:`FixedwingPhysics`; the
commands are the model's inputs (a multicopter's motors; a plane's throttle, aileron, elevator, rudder).

Randomness: every noise source (wind, IMU, magnetometer, barometer, GPS, airspeed) draws from its own
``random.Random`` seeded from ``f"{seed}/{name}"``, so the same seed gives the same run, sample for
sample, and changing one sensor's configuration leaves the others' noise untouched.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

from stack.airframe.model import FixedwingModel, VehicleModel, load_vehicle
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import IDENTITY, Quat, rotate_inv
from stack.mathlib.vector import ZERO3, Vec3
from stack.params import catalogue
from stack.sim.airspeed_sensor import AirspeedModel, AirspeedParams, AirspeedSample
from stack.sim.fixedwing_physics import FixedwingPhysics
from stack.sim.physics import SIH_MAX_BODY_RATE, MulticopterPhysics
from stack.sim.sensors import (
    BarometerModel,
    BaroParams,
    BaroSample,
    GpsModel,
    GpsParams,
    GpsSample,
    ImuModel,
    ImuParams,
    ImuSample,
    MagnetometerModel,
    MagParams,
    MagSample,
)
from stack.sim.wind import WindModel, WindParams

SIH_HOME: tuple[float, float, float] = (
    float(catalogue.get("SIH_LOC_LAT0").default),
    float(catalogue.get("SIH_LOC_LON0").default),
    float(catalogue.get("SIH_LOC_H0").default),
)
"""The default home: SIH_LOC_LAT0 (deg), SIH_LOC_LON0 (deg), SIH_LOC_H0 (m AMSL)."""

SensorSample = ImuSample | MagSample | BaroSample | GpsSample | AirspeedSample


class GroundTruth(NamedTuple):
    """True state for the ground-truth topic (field names follow ``SimGroundtruth``)."""

    time_us: int
    position: Vec3  # NED about home, m
    velocity: Vec3  # NED, m/s
    acceleration: Vec3  # NED, m/s² (mean over the last physics step)
    q: Quat  # body FRD → NED
    angular_velocity: Vec3  # FRD, rad/s
    angular_acceleration: Vec3  # FRD, rad/s²
    specific_force: Vec3  # FRD, m/s² (an ideal accelerometer)
    lat: float  # deg
    lon: float  # deg
    alt: float  # m AMSL
    on_ground: bool
    wind: Vec3  # NED, m/s
    motors: tuple[float, ...]  # motor states in [0, 1] (a plane's: its throttle state)


def sensor_rng(seed: int, name: str) -> random.Random:
    """The random stream of one noise source: a function of the run seed and the source's name only."""
    return random.Random(f"{seed}/{name}")


def _period_us(rate_hz: float, what: str) -> int:
    if not rate_hz > 0.0:
        raise ValueError(f"{what} must be > 0 Hz, got {rate_hz}")
    period = round(1e6 / rate_hz)
    if period < 1:
        raise ValueError(f"{what} of {rate_hz} Hz is above 1 MHz")
    return period


MAX_CATCH_UP_STEPS = 25
"""On the wall clock a simulation running late runs the steps it missed back to back, up to this many (100 ms at
250 Hz); later than that the missed time is skipped (and counted)."""


class Simulator:
    """A seeded simulation: physics, wind, IMU, magnetometer, barometer, GPS, and a plane's airspeed.

    Parameters (rates in Hz; PX4 names where PX4 has one):

    - ``model``: a :class:`VehicleModel`, a :class:`FixedwingModel` or a vehicle name/path for
      :func:`load_vehicle` (default the SIH quad).
    - ``seed``: run seed; the same seed and inputs give identical samples.
    - ``physics_rate_hz`` (1000): the plant's step rate (a multicopter's RK4; a plane's semi-implicit
      Euler, for which 500 is enough); its period must be a whole number of µs.
    - ``imu_rate_hz`` (250; PX4 SITL IMU_INTEG_RATE): the :meth:`advance` period; a whole multiple
      of the physics period.
    - ``mag_rate_hz`` (50), ``baro_rate_hz`` (20), ``gps_rate_hz`` (10): sampled at the first IMU tick
      at or after each period, starting with the first tick; at most the IMU rate.
    - ``home``: (lat deg, lon deg, alt m AMSL) of NED origin and ground (SIH_LOC_LAT0/LON0/H0).
    - ``wind``, ``imu``, ``mag``, ``baro``, ``gps``: parameter sets (defaults: calm, see ``sensors``).
    - ``airspeed``: the airspeed sensor's noise, offset and rate (fixed-wing only; default 1 Pa, 20 Hz). It
      reads the forward (body x) component of the air-relative velocity at the altitude AMSL.
    - ``max_body_rate``: body-rate clamp (rad/s, SIH 6π).

    The wind is advanced once per :meth:`advance` and held over its physics steps.
    """

    __slots__ = (
        "_airspeed",
        "_airspeed_due",
        "_airspeed_period",
        "_applied_wind",
        "_baro",
        "_baro_due",
        "_baro_period",
        "_gps",
        "_gps_due",
        "_gps_period",
        "_home_alt",
        "_imu",
        "_imu_dt",
        "_imu_period",
        "_imu_rate",
        "_mag",
        "_mag_due",
        "_mag_period",
        "_physics_dt",
        "_projection",
        "_substeps",
        "_time_us",
        "_wind",
        "home",
        "model",
        "physics",
        "seed",
    )

    def __init__(
        self,
        model: VehicleModel | str | Path = "sih_quad",
        seed: int = 0,
        physics_rate_hz: float = 1000.0,
        imu_rate_hz: float = 250.0,
        mag_rate_hz: float = 50.0,
        baro_rate_hz: float = 20.0,
        gps_rate_hz: float = 10.0,
        home: tuple[float, float, float] = SIH_HOME,
        wind: WindParams | None = None,
        imu: ImuParams | None = None,
        mag: MagParams | None = None,
        baro: BaroParams | None = None,
        gps: GpsParams | None = None,
        max_body_rate: float = SIH_MAX_BODY_RATE,
        airspeed: AirspeedParams | None = None,
    ) -> None:
        self.model = model if isinstance(model, VehicleModel | FixedwingModel) else load_vehicle(model)
        self.seed = seed
        physics_period = _period_us(physics_rate_hz, "physics_rate_hz")
        if abs(1e6 / physics_rate_hz - physics_period) > 1e-6:
            raise ValueError(f"physics_rate_hz {physics_rate_hz} does not give a whole-µs period")
        self._imu_period = _period_us(imu_rate_hz, "imu_rate_hz")
        if abs(1e6 / imu_rate_hz - self._imu_period) > 1e-6 or self._imu_period % physics_period:
            raise ValueError(
                f"the IMU period (1/{imu_rate_hz} s) must be a whole multiple of the physics period "
                f"({physics_period} µs)"
            )
        self._substeps = self._imu_period // physics_period
        self._physics_dt = physics_period * 1e-6
        self._imu_dt = self._imu_period * 1e-6
        self._imu_rate = 1e6 / self._imu_period
        self._mag_period = _period_us(mag_rate_hz, "mag_rate_hz")
        self._baro_period = _period_us(baro_rate_hz, "baro_rate_hz")
        self._gps_period = _period_us(gps_rate_hz, "gps_rate_hz")
        for name, period in (("mag", self._mag_period), ("baro", self._baro_period), ("gps", self._gps_period)):
            if period < self._imu_period:
                raise ValueError(f"{name}_rate_hz must not exceed imu_rate_hz")
        self.home = home
        self._projection = MapProjection(home[0], home[1])
        self._home_alt = home[2]
        self.physics: MulticopterPhysics | FixedwingPhysics
        self._airspeed: AirspeedModel | None = None
        self._airspeed_period = 0
        if isinstance(self.model, FixedwingModel):
            self.physics = FixedwingPhysics(self.model, home_altitude=home[2], max_body_rate=max_body_rate)
            airspeed = airspeed if airspeed is not None else AirspeedParams()
            self._airspeed_period = _period_us(airspeed.rate_hz, "airspeed rate_hz")
            if self._airspeed_period < self._imu_period:
                raise ValueError("the airspeed rate must not exceed imu_rate_hz")
            self._airspeed = AirspeedModel(airspeed, sensor_rng(seed, "airspeed"))
        else:
            self.physics = MulticopterPhysics(self.model, max_body_rate=max_body_rate)
        self._wind = WindModel(wind if wind is not None else WindParams(), sensor_rng(seed, "wind"))
        self._applied_wind = self._wind.wind
        self._imu = ImuModel(imu if imu is not None else ImuParams(), imu_rate_hz, sensor_rng(seed, "imu"))
        self._mag = MagnetometerModel(mag if mag is not None else MagParams(), sensor_rng(seed, "mag"))
        self._baro = BarometerModel(baro if baro is not None else BaroParams(), sensor_rng(seed, "baro"))
        self._gps = GpsModel(gps if gps is not None else GpsParams(), gps_rate_hz, self._projection, home[2],
                             sensor_rng(seed, "gps"))
        self._time_us = 0
        self._mag_due = self._baro_due = self._gps_due = self._airspeed_due = self._imu_period

    @property
    def time_us(self) -> int:
        """Simulated time (µs since start)."""
        return self._time_us

    @property
    def imu_period_us(self) -> int:
        return self._imu_period

    @property
    def imu(self) -> ImuModel:
        return self._imu

    @property
    def magnetometer(self) -> MagnetometerModel:
        return self._mag

    @property
    def wind(self) -> Vec3:
        """The wind NED (m/s) acting on the vehicle over the current IMU period (at its height)."""
        return self._applied_wind

    def advance(self, motor_commands: Sequence[float]) -> list[SensorSample]:
        """Advance one IMU period with these commands held; return the samples due.

        The commands are the model's inputs: [0, 1] per rotor, or a plane's (throttle, aileron, elevator, rudder).
        """
        self._wind.update(self._imu_dt)
        wind = self._applied_wind = self._wind.at_height(-self.physics.position[2])
        physics = self.physics
        step = physics.step
        dt = self._physics_dt
        v0x, v0y, v0z = physics.velocity
        for _ in range(self._substeps):
            step(dt, motor_commands, wind)
        t = self._time_us + self._imu_period
        self._time_us = t
        v1x, v1y, v1z = physics.velocity
        rate = self._imu_rate
        specific_force = rotate_inv(
            physics.attitude, ((v1x - v0x) * rate, (v1y - v0y) * rate, (v1z - v0z) * rate - physics.gravity)
        )
        samples: list[SensorSample] = [self._imu.sample(t, physics.angular_velocity, specific_force)]
        if t >= self._mag_due:
            samples.append(self._mag.sample(t, physics.attitude))
            self._mag_due = self._next_due(self._mag_due, self._mag_period, t)
        if t >= self._baro_due:
            samples.append(self._baro.sample(t, self._home_alt - physics.position[2]))
            self._baro_due = self._next_due(self._baro_due, self._baro_period, t)
        if t >= self._gps_due:
            self._gps.measure(t, physics.position, physics.velocity)
            self._gps_due = self._next_due(self._gps_due, self._gps_period, t)
        gps = self._gps.pop_due(t)
        while gps is not None:
            samples.append(gps)
            gps = self._gps.pop_due(t)
        if self._airspeed is not None and t >= self._airspeed_due:
            vx, vy, vz = physics.velocity
            forward = rotate_inv(physics.attitude, (vx - wind[0], vy - wind[1], vz - wind[2]))[0]
            samples.append(self._airspeed.sample(t, forward, self._home_alt - physics.position[2]))
            self._airspeed_due = self._next_due(self._airspeed_due, self._airspeed_period, t)
        return samples

    @staticmethod
    def _next_due(due: int, period: int, now: int) -> int:
        due += period
        while due <= now:
            due += period
        return due

    def truth(self) -> GroundTruth:
        """Snapshot of the true state now, for the ground-truth topic."""
        p = self.physics
        north, east, down = p.position
        lat, lon = self._projection.reproject(north, east)
        return GroundTruth(
            time_us=self._time_us,
            position=p.position,
            velocity=p.velocity,
            acceleration=p.acceleration,
            q=p.attitude,
            angular_velocity=p.angular_velocity,
            angular_acceleration=p.angular_acceleration,
            specific_force=p.specific_force,
            lat=lat,
            lon=lon,
            alt=self._home_alt - down,
            on_ground=p.on_ground,
            wind=self._applied_wind,
            motors=p.motor_states,
        )

    # Failure injection and scenario control.

    @property
    def gps_enabled(self) -> bool:
        return self._gps.enabled

    def set_gps_enabled(self, enabled: bool) -> None:
        """GPS on/off; while off, GPS samples report no fix (fix_type 0, NaN position)."""
        self._gps.set_enabled(enabled)

    @property
    def wind_enabled(self) -> bool:
        return self._wind.enabled

    def set_wind_enabled(self, enabled: bool) -> None:
        """Wind on/off; off means exactly zero wind."""
        self._wind.set_enabled(enabled)
        self._applied_wind = self._wind.at_height(-self.physics.position[2])

    def set_wind(self, params: WindParams) -> None:
        """New wind figures (mean, gusts, enabled), applied from the next step."""
        self._wind.set_params(params)

    def reset_pose(
        self,
        position: Vec3 = ZERO3,
        attitude: Quat = IDENTITY,
        velocity: Vec3 = ZERO3,
        angular_velocity: Vec3 = ZERO3,
        motor_states: Sequence[float] | None = None,
    ) -> None:
        """Put the vehicle at a pose (NED m, body → NED quaternion) without touching the clock.

        Motors are stopped unless ``motor_states`` is given; GPS measurements not yet published are dropped.
        At or below z = 0 the vehicle is placed on the ground, at rest (a multicopter level, a plane on its gear).
        """
        self.physics.reset(position, velocity, attitude, angular_velocity, motor_states)
        self._gps.clear()
