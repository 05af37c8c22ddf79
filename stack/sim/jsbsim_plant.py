"""An independent flight model: a packaged JSBSim aircraft as the simulator's plant.

:class:`JsbsimPlant` has the interface of :class:`stack.sim.simulator.Simulator` (``advance``,
``truth``, the clock, the failure and wind switches, ``reset_pose``) but the physics are JSBSim's
(PyPI ``jsbsim``): aerodynamics, piston engine and propeller, landing gear and brakes of an aircraft
nobody on this project wrote. The sensors are the stack's own models (IMU, magnetometer, barometer,
GPS, airspeed), seeded per sensor exactly as the simulator seeds them, fed from JSBSim's state
converted to the stack's frames.

Frames and units. JSBSim's body axes are x forward, y right, z down (FRD); its Euler angles φ, θ, ψ are
the 3-2-1 rotation from the local geodetic NED frame to the body, so the body → NED quaternion is
:func:`stack.mathlib.quaternion.from_euler` of them. Positions are JSBSim's geodetic latitude,
longitude and altitude, projected about home with the stack's :class:`MapProjection` (as PX4 projects
a real GPS), velocities are JSBSim's NED velocities relative to the ground, body rates are relative
to the Earth (``velocities/p-rad_sec``: the gyro leaves out the 7e-5 rad/s of Earth rotation, as SIH
does). JSBSim works in feet; everything here leaves in SI units.

The accelerometer reads JSBSim's specific force at the centre of gravity: all non-gravitational
forces over the mass, ground friction included (``accelerations/N{x,y,z}``, in units of JSBSim's
standard g, ``FGAuxiliary``), averaged over the physics steps of the IMU period.

The wind is the stack's :class:`WindModel` (mean wind and gusts, seeded), written into JSBSim's
atmosphere (``atmosphere/wind-{north,east,down}-fps``) once per IMU period, so JSBSim flies in the
same air the truth reports; JSBSim's own turbulence stays off.

Runway. The aircraft starts on the ground at home (terrain elevation = home altitude), heading
``heading_deg`` (the runway's direction), engine running at idle, at rest: before time 0 it is settled
on its gear on the brakes, so its gear deflections and idle rpm are in equilibrium when the stack
starts. The stack's actuator convention has no brake output (PX4's has none for a plane), so the
plant brakes as a pilot would: while the throttle is below ``brakes.below_throttle`` and all the
``ground_contacts`` touch the ground (nose wheel down). At rest that is the parking brake (the idle
thrust of a piston engine would otherwise roll the aircraft at a walking pace); after a landing it is
the roll-out braking. Any throttle above the threshold releases them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import jsbsim

from stack.airframe.jsbsim import CHANNELS, JsbsimAircraft
from stack.airframe.model import load_vehicle
from stack.mathlib import quaternion as quat
from stack.mathlib.geo import MapProjection
from stack.mathlib.quaternion import IDENTITY, Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import ZERO3, Vec3
from stack.sim.airspeed_sensor import AirspeedModel, AirspeedParams, AirspeedSample
from stack.sim.sensors import (
    BarometerModel,
    BaroParams,
    GpsModel,
    GpsParams,
    ImuModel,
    ImuParams,
    MagnetometerModel,
    MagParams,
)
from stack.sim.simulator import SIH_HOME, GroundTruth, SensorSample, sensor_rng
from stack.sim.wind import WindModel, WindParams

FT = 0.3048  # m per ft, JSBSim's length unit
SLUG = 14.593903  # kg per slug, its mass unit
GROUND_SETTLE_TIME = 1.0
"""s on the brakes after the aircraft is put back in its ground equilibrium with the exact heading."""

JsbsimSample = SensorSample | AirspeedSample


def _period_us(rate_hz: float, what: str) -> int:
    if not rate_hz > 0.0:
        raise ValueError(f"{what} must be > 0 Hz, got {rate_hz}")
    period = round(1e6 / rate_hz)
    if period < 1 or abs(1e6 / rate_hz - period) > 1e-6:
        raise ValueError(f"{what} of {rate_hz} Hz does not give a whole-µs period")
    return period


def _next_due(due: int, period: int, now: int) -> int:
    due += period
    while due <= now:
        due += period
    return due


class JsbsimPlant:
    """A seeded JSBSim simulation with the stack's sensors; the :class:`Simulator` interface for a plane.

    Parameters as :class:`Simulator`'s (rates in Hz):

    - ``model``: a :class:`JsbsimAircraft` or a vehicle name/path for :func:`~stack.airframe.model.load_vehicle`.
    - ``seed``: run seed; the same seed and inputs give identical samples.
    - ``physics_rate_hz`` (1000): JSBSim's step rate; the IMU period must be a whole number of its steps.
    - ``imu_rate_hz`` (250): the :meth:`advance` period. ``mag_rate_hz`` (50), ``baro_rate_hz`` (20),
      ``gps_rate_hz`` (10) and ``airspeed.rate_hz`` (20): sampled at the first IMU tick at or after
      each period, starting with the first tick; at most the IMU rate.
    - ``home``: (lat deg, lon deg, alt m AMSL) of the NED origin and of the runway.
    - ``wind``, ``imu``, ``mag``, ``baro``, ``gps``, ``airspeed``: parameter sets (defaults: calm, the
      sensors' defaults).

    :meth:`advance` takes the actuator outputs in the plane's convention: throttle [0, 1], then
    aileron, elevator, rudder in [−1, 1] (+ = positive roll, pitch, yaw torque); a non-finite output
    counts as 0 (idle, neutral) and values are clamped to their range.
    """

    __slots__ = (
        "_airspeed",
        "_airspeed_due",
        "_airspeed_period",
        "_applied_wind",
        "_baro",
        "_baro_due",
        "_baro_period",
        "_contacts",
        "_gps",
        "_gps_due",
        "_gps_period",
        "_ground_pose",
        "_home_alt",
        "_imu",
        "_imu_period",
        "_mag",
        "_mag_due",
        "_mag_period",
        "_projection",
        "_specific_force",
        "_substeps",
        "_time_us",
        "_wind",
        "fdm",
        "home",
        "model",
        "seed",
    )

    def __init__(
        self,
        model: JsbsimAircraft | str | Path = "jsbsim_c172",
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
        airspeed: AirspeedParams | None = None,
    ) -> None:
        self.model = model if isinstance(model, JsbsimAircraft) else _load(model)
        self.seed = seed
        physics_period = _period_us(physics_rate_hz, "physics_rate_hz")
        self._imu_period = _period_us(imu_rate_hz, "imu_rate_hz")
        if self._imu_period % physics_period:
            raise ValueError(
                f"the IMU period (1/{imu_rate_hz} s) must be a whole multiple of the physics period "
                f"({physics_period} µs)"
            )
        self._substeps = self._imu_period // physics_period
        airspeed = airspeed if airspeed is not None else AirspeedParams()
        self._mag_period = _period_us(mag_rate_hz, "mag_rate_hz")
        self._baro_period = _period_us(baro_rate_hz, "baro_rate_hz")
        self._gps_period = _period_us(gps_rate_hz, "gps_rate_hz")
        self._airspeed_period = _period_us(airspeed.rate_hz, "airspeed rate_hz")
        for name, period in (
            ("mag", self._mag_period),
            ("baro", self._baro_period),
            ("gps", self._gps_period),
            ("airspeed", self._airspeed_period),
        ):
            if period < self._imu_period:
                raise ValueError(f"the {name} rate must not exceed imu_rate_hz")
        self.home = home
        self._projection = MapProjection(home[0], home[1])
        self._home_alt = home[2]
        self._wind = WindModel(wind if wind is not None else WindParams(), sensor_rng(seed, "wind"))
        self._applied_wind = self._wind.wind
        self._imu = ImuModel(imu if imu is not None else ImuParams(), imu_rate_hz, sensor_rng(seed, "imu"))
        self._mag = MagnetometerModel(mag if mag is not None else MagParams(), sensor_rng(seed, "mag"))
        self._baro = BarometerModel(baro if baro is not None else BaroParams(), sensor_rng(seed, "baro"))
        self._gps = GpsModel(gps if gps is not None else GpsParams(), gps_rate_hz, self._projection, home[2],
                             sensor_rng(seed, "gps"))
        self._airspeed = AirspeedModel(airspeed, sensor_rng(seed, "airspeed"))
        self._contacts = tuple(f"gear/unit[{i}]/WOW" for i in self.model.ground_contacts)
        self.fdm = self._load(physics_period * 1e-6)
        self._ground_pose = self._settle_on_runway()
        self._specific_force = self._read_specific_force()
        self._time_us = 0
        self._mag_due = self._baro_due = self._gps_due = self._airspeed_due = self._imu_period

    def _load(self, dt: float) -> Any:
        jsbsim.FGJSBBase().debug_lvl = 0  # no banner or model echo on stdout
        fdm = jsbsim.FGFDMExec(None)  # the aircraft, engines and systems packaged with the wheel
        if not fdm.load_model(self.model.aircraft):
            raise ValueError(f"{Path(self.model.path).name}: jsbsim.aircraft: JSBSim has no aircraft "
                             f"{self.model.aircraft!r}")
        fdm.set_dt(dt)
        model = self.model
        names = [
            *model.initial_properties,
            *(t.property for targets in model.controls for t in targets),
            *model.brakes.properties,
            *self._contacts,
        ]
        properties = fdm.get_property_manager()
        for name in names:
            if not properties.hasNode(name):
                raise ValueError(f"{Path(model.path).name}: JSBSim's {model.aircraft} has no property {name!r}")
        fdm["ic/terrain-elevation-ft"] = self._home_alt / FT
        return fdm

    def _initial_conditions(self, lat: float, lon: float, agl: float, euler: Vec3) -> None:
        """Put the aircraft at rest at a place and attitude (JSBSim ``run_ic``; the engine keeps running)."""
        fdm = self.fdm
        fdm["ic/lat-geod-deg"] = lat
        fdm["ic/long-gc-deg"] = lon
        fdm["ic/h-agl-ft"] = agl / FT
        fdm["ic/phi-rad"], fdm["ic/theta-rad"], fdm["ic/psi-true-rad"] = euler
        for name in ("ic/u-fps", "ic/v-fps", "ic/w-fps", "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec"):
            fdm[name] = 0.0
        fdm.run_ic()

    def _settle_on_runway(self) -> tuple[float, float, float]:
        """Settle the aircraft on its gear at home before time 0; return its ground pose (CG height, roll, pitch).

        From a first guess (CG on the runway) the gear springs the aircraft up and it settles on the brakes
        with the engine starting; the settled height and attitude are then set again with the exact heading
        and zero speed, and settled once more.
        """
        fdm = self.fdm
        lat, lon, _ = self.home
        heading = math.radians(self.model.heading_deg)
        self._initial_conditions(lat, lon, 0.0, (0.0, 0.0, heading))
        for name, value in self.model.initial_properties.items():
            fdm[name] = value
        self._apply_controls((0.0, 0.0, 0.0, 0.0))
        for _ in range(round(self.model.settle_time / fdm.get_delta_t())):
            fdm.run()
        pose = (fdm["position/h-agl-ft"] * FT, fdm["attitude/phi-rad"], fdm["attitude/theta-rad"])
        self._initial_conditions(lat, lon, pose[0], (pose[1], pose[2], heading))
        for _ in range(round(GROUND_SETTLE_TIME / fdm.get_delta_t())):
            fdm.run()
        return pose

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
        """The wind NED (m/s) acting over the current IMU period (at the aircraft's height)."""
        return self._applied_wind

    @property
    def mass(self) -> float:
        """The aircraft's mass now (kg; JSBSim's, fuel burn included)."""
        return self.fdm["inertia/mass-slugs"] * SLUG

    @property
    def on_ground(self) -> bool:
        """Any wheel touches the ground."""
        fdm = self.fdm
        return any(fdm[c] for c in self._contacts)

    def _apply_controls(self, commands: Sequence[float]) -> None:
        """Write the actuator outputs into JSBSim's controls and set the brakes."""
        if len(commands) < len(CHANNELS):
            raise ValueError(f"expected {len(CHANNELS)} actuator outputs (throttle, aileron, elevator, rudder), "
                             f"got {len(commands)}")
        fdm = self.fdm
        throttle = 0.0
        for i, targets in enumerate(self.model.controls):
            value = float(commands[i])
            if not math.isfinite(value):
                value = 0.0
            value = min(max(value, 0.0 if i == 0 else -1.0), 1.0)
            if i == 0:
                throttle = value
            for target in targets:
                fdm[target.property] = target.gain * value
        brakes = self.model.brakes
        braking = throttle < brakes.below_throttle and all(fdm[c] for c in self._contacts)
        for name in brakes.properties:
            fdm[name] = brakes.command if braking else 0.0

    def _read_specific_force(self) -> Vec3:
        fdm = self.fdm
        # JSBSim's load factors are the specific force in units of its standard g (32.174 ft/s² = 9.80665 m/s²),
        # with Nz positive up.
        return (
            fdm["accelerations/Nx"] * CONSTANTS_ONE_G,
            fdm["accelerations/Ny"] * CONSTANTS_ONE_G,
            -fdm["accelerations/Nz"] * CONSTANTS_ONE_G,
        )

    def _attitude(self) -> Quat:
        fdm = self.fdm
        return quat.canonical(
            quat.from_euler(fdm["attitude/phi-rad"], fdm["attitude/theta-rad"], fdm["attitude/psi-rad"])
        )

    def _position(self) -> tuple[Vec3, float, float, float]:
        """NED position about home (m), and latitude, longitude (deg) and altitude AMSL (m)."""
        fdm = self.fdm
        lat, lon = fdm["position/lat-geod-deg"], fdm["position/long-gc-deg"]
        alt = fdm["position/h-sl-ft"] * FT
        north, east = self._projection.project(lat, lon)
        return (north, east, self._home_alt - alt), lat, lon, alt

    def _velocity(self) -> Vec3:
        fdm = self.fdm
        return (fdm["velocities/v-north-fps"] * FT, fdm["velocities/v-east-fps"] * FT,
                fdm["velocities/v-down-fps"] * FT)

    def _body_rates(self) -> Vec3:
        fdm = self.fdm
        return fdm["velocities/p-rad_sec"], fdm["velocities/q-rad_sec"], fdm["velocities/r-rad_sec"]

    def advance(self, commands: Sequence[float]) -> list[JsbsimSample]:
        """Advance one IMU period with these actuator outputs (throttle, aileron, elevator, rudder); return
        the samples due."""
        fdm = self.fdm
        self._wind.update(self._imu_period * 1e-6)
        wn, we, wd = self._applied_wind = self._wind.at_height(fdm["position/h-agl-ft"] * FT)
        fdm["atmosphere/wind-north-fps"] = wn / FT
        fdm["atmosphere/wind-east-fps"] = we / FT
        fdm["atmosphere/wind-down-fps"] = wd / FT
        self._apply_controls(commands)
        fx = fy = fz = 0.0
        run = fdm.run
        for _ in range(self._substeps):
            run()
            nx, ny, nz = fdm["accelerations/Nx"], fdm["accelerations/Ny"], fdm["accelerations/Nz"]
            fx += nx
            fy += ny
            fz += nz
        scale = CONSTANTS_ONE_G / self._substeps
        self._specific_force = (fx * scale, fy * scale, -fz * scale)
        t = self._time_us + self._imu_period
        self._time_us = t
        attitude = self._attitude()
        samples: list[JsbsimSample] = [self._imu.sample(t, self._body_rates(), self._specific_force)]
        if t >= self._mag_due:
            samples.append(self._mag.sample(t, attitude))
            self._mag_due = _next_due(self._mag_due, self._mag_period, t)
        altitude = fdm["position/h-sl-ft"] * FT
        if t >= self._baro_due:
            samples.append(self._baro.sample(t, altitude))
            self._baro_due = _next_due(self._baro_due, self._baro_period, t)
        if t >= self._gps_due:
            position, _, _, _ = self._position()
            self._gps.measure(t, position, self._velocity())
            self._gps_due = _next_due(self._gps_due, self._gps_period, t)
        gps = self._gps.pop_due(t)
        while gps is not None:
            samples.append(gps)
            gps = self._gps.pop_due(t)
        if t >= self._airspeed_due:
            samples.append(self._airspeed.sample(t, fdm["velocities/u-aero-fps"] * FT, altitude))
            self._airspeed_due = _next_due(self._airspeed_due, self._airspeed_period, t)
        return samples

    def truth(self) -> GroundTruth:
        """Snapshot of the true state now, for the ground-truth topic."""
        fdm = self.fdm
        position, lat, lon, alt = self._position()
        attitude = self._attitude()
        gravity = (0.0, 0.0, CONSTANTS_ONE_G)
        acceleration = quat.rotate(attitude, self._specific_force)
        return GroundTruth(
            time_us=self._time_us,
            position=position,
            velocity=self._velocity(),
            acceleration=(acceleration[0] + gravity[0], acceleration[1] + gravity[1], acceleration[2] + gravity[2]),
            q=attitude,
            angular_velocity=self._body_rates(),
            angular_acceleration=(
                fdm["accelerations/pdot-rad_sec2"],
                fdm["accelerations/qdot-rad_sec2"],
                fdm["accelerations/rdot-rad_sec2"],
            ),
            specific_force=self._specific_force,
            lat=lat,
            lon=lon,
            alt=alt,
            on_ground=self.on_ground,
            wind=self._applied_wind,
            motors=(fdm["fcs/throttle-pos-norm"],),
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

    def set_wind(self, params: WindParams) -> None:
        """New wind figures (mean, gusts, enabled), applied from the next step."""
        self._wind.set_params(params)

    def reset_pose(
        self,
        position: Vec3 = ZERO3,
        attitude: Quat = IDENTITY,
        velocity: Vec3 = ZERO3,
        angular_velocity: Vec3 = ZERO3,
    ) -> None:
        """Put the aircraft at a pose (NED m about home, body → NED quaternion) without touching the clock.

        With the centre of gravity at or below its height at rest on the gear, the aircraft is put on the
        runway at rest in its ground attitude, with the heading of ``attitude``; otherwise it flies from the
        given attitude, NED velocity (relative to the ground) and body rates. The engine keeps running.
        GPS measurements not yet published are dropped.
        """
        north, east, down = position
        lat, lon = self._projection.reproject(north, east)
        roll, pitch, yaw = quat.to_euler(attitude)
        if not all(math.isfinite(v) for v in (*position, roll, pitch, yaw, *velocity, *angular_velocity)):
            raise ValueError("reset_pose needs a finite position, attitude, velocity and angular velocity")
        ground_height, ground_roll, ground_pitch = self._ground_pose
        height = -down  # above the runway, which is at the home altitude
        if height <= ground_height:
            self._initial_conditions(lat, lon, ground_height, (ground_roll, ground_pitch, yaw))
        else:
            fdm = self.fdm
            fdm["ic/lat-geod-deg"] = lat
            fdm["ic/long-gc-deg"] = lon
            fdm["ic/h-sl-ft"] = (self._home_alt - down) / FT
            fdm["ic/phi-rad"], fdm["ic/theta-rad"], fdm["ic/psi-true-rad"] = roll, pitch, yaw
            fdm["ic/vn-fps"], fdm["ic/ve-fps"], fdm["ic/vd-fps"] = (v / FT for v in velocity)
            fdm["ic/p-rad_sec"], fdm["ic/q-rad_sec"], fdm["ic/r-rad_sec"] = angular_velocity
            fdm.run_ic()
        self._specific_force = self._read_specific_force()
        self._gps.clear()


def _load(name_or_path: str | Path) -> JsbsimAircraft:
    model = load_vehicle(name_or_path)
    if not isinstance(model, JsbsimAircraft):
        raise ValueError(f"vehicle {name_or_path}: not a JSBSim aircraft (type = \"jsbsim\")")
    return model
