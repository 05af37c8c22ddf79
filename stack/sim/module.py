"""The simulator module: the default plant, and the lockstep coordinator of a simulated stack.

Each step it reads the latest ``actuator_outputs_sim`` (a multicopter's motors; a plane's throttle,
aileron, elevator and rudder in output[0..3]), advances the physics by one IMU period and publishes
the sensors that fell due (accelerometer before gyro, the estimator's trigger; a plane's airspeed),
the ground truth and, at 10 Hz, the battery (PX4's battery simulator: drains while armed). A multicopter whose
flight stack falls silent while armed (its flight-control host lost) is flown down by the plant's own autopilot, as a
Pixhawk on Offboard loss (:mod:`stack.sim.command_loss`). In lockstep it drives
simulated time; with ``--realtime`` it is paced by the wall clock and keeps to it: a run that comes late (a busy
machine) runs the steps missed back to back, up to MAX_CATCH_UP_STEPS; beyond that the missed time is skipped
(the physics does not see it) and counted. Otherwise simulated time would fall behind the wall clock for good,
the vehicle flying in slow motion under controllers and setpoints timed on the wall clock (on a busy 2-core
machine it fell 3.5 s behind in a minute, the position loop went unstable and the vehicle crashed).
"""

from __future__ import annotations

import math

from stack.airframe.model import FixedwingModel, VehicleModel, load_vehicle
from stack.commander.command_checks import addressed_to
from stack.mathlib.vector import Vec3
from stack.msg.fixedwing import Airspeed
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorBaro, SensorGps, SensorGyro, SensorMag
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import ActuatorArmed, BatteryStatus, VehicleCommand
from stack.params import catalogue
from stack.params.binding import combine
from stack.runtime.module import Arg, Module
from stack.runtime.priority import PLANT
from stack.sim import battery, command_loss
from stack.sim.airspeed_sensor import AirspeedSample
from stack.sim.battery import BatteryModel
from stack.sim.command_loss import CommandLossFailsafe
from stack.sim.sensors import BaroSample, GpsSample, ImuSample, MagSample
from stack.sim.simulator import MAX_CATCH_UP_STEPS, GroundTruth, Simulator
from stack.sim.wind import WindParams

# Device ids as PX4's simulated drivers report them (SIH's IMU id; the others distinct).
IMU_DEVICE_ID = 1310988
MAG_DEVICE_ID = 197388
BARO_DEVICE_ID = 6620172
GPS_DEVICE_ID = 11469064
AIRSPEED_DEVICE_ID = 1377548  # DRV_DIFF_PRESS_DEVTYPE_SIM, bus 1, address 5, simulation


class SimulatorModule(Module):
    NAME = "simulator"
    WORK_QUEUE = PLANT
    DESCRIPTION = "Rigid-body simulator (PX4 SIH-like), multicopter or airplane: physics, sensors, ground truth"
    LOCKSTEP_COORDINATOR = True
    ARGS = (
        Arg("vehicle", "sih_quad", "Vehicle model: a name in stack/airframe/vehicles or a path to a model file"),
        Arg("imu_rate_hz", 250.0, "IMU rate = lockstep step rate (PX4 SITL IMU_INTEG_RATE)"),
        Arg("physics_rate_hz", 1000.0, "Physics step rate (a multicopter's RK4; for the SIH airplane 500 is enough)"),
        Arg("mag_rate_hz", 50.0),
        Arg("baro_rate_hz", 20.0),
        Arg("gps_rate_hz", 10.0),
        Arg("gps_delay_s", 0.0, "GPS measurement delay"),
    )
    PARAMS = combine(
        catalogue.params(
            "SIH_LOC_LAT0", "SIH_LOC_LON0", "SIH_LOC_H0", "SIM_GPS_USED", "SIM_WIND_SPD", "SIM_WIND_DIR",
            "SIM_WIND_GUST", "SIM_WIND_GUST_T", "SIM_WIND_HREF", "SYS_FAILURE_EN", "MAV_SYS_ID", "MAV_COMP_ID",
        ),
        battery.PARAMS,
        command_loss.PARAMS,
    )
    PUBLISHES = (
        ORB_ID.sensor_accel,
        ORB_ID.sensor_gyro,
        ORB_ID.sensor_mag,
        ORB_ID.sensor_baro,
        ORB_ID.sensor_gps,
        ORB_ID.sim_groundtruth,
        ORB_ID.airspeed,
        ORB_ID.battery_status,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        p, a = self.params, self.args
        model = load_vehicle(str(a["vehicle"]))
        plant = Simulator if isinstance(model, VehicleModel | FixedwingModel) else _jsbsim_plant()
        self.sim = plant(
            model=model,
            seed=rt.spec.seed,
            physics_rate_hz=float(a["physics_rate_hz"]),
            imu_rate_hz=float(a["imu_rate_hz"]),
            mag_rate_hz=float(a["mag_rate_hz"]),
            baro_rate_hz=float(a["baro_rate_hz"]),
            gps_rate_hz=float(a["gps_rate_hz"]),
            home=(float(p["SIH_LOC_LAT0"]), float(p["SIH_LOC_LON0"]), float(p["SIH_LOC_H0"])),
            wind=self._wind_params(),
        )
        self.sim.set_gps_enabled(int(p["SIM_GPS_USED"]) >= 4)
        self.input_count = model.input_count
        self.truth: GroundTruth = self.sim.truth()
        self.imu: ImuSample | None = None
        """The plant's last state and IMU sample, which the takeover flies on."""
        self.takeover = (
            CommandLossFailsafe(self.params.values(), model, self.sim.imu_period_us)
            if isinstance(model, VehicleModel)
            else None
        )
        self._stack_disarmed_seen = False
        """Whether the stack has said disarmed since this plant started (:meth:`_stack_arming`)."""
        self._said_armed_before = False
        self.subscribe(ORB_ID.actuator_outputs_sim)
        self.subscribe(ORB_ID.actuator_armed)
        self.subscribe(ORB_ID.vehicle_command, queue=True)
        for topic in self.PUBLISHES:
            if topic is not ORB_ID.airspeed or not isinstance(model, VehicleModel):  # a multicopter has no pitot
                self.advertise(topic)
        self.battery = BatteryModel(self.params.values())
        self._battery_due_us = 0
        self.epoch_us: int | None = None
        self.catch_up_steps = 0
        self.skipped_steps = 0
        if isinstance(model, FixedwingModel):
            self.log.info(
                "vehicle %s: fixed-wing, %.3f kg, %.1f N static thrust",
                model.name,
                model.mass,
                model.thruster.max_thrust,
            )
        elif not isinstance(model, VehicleModel):
            self.log.info("vehicle %s: JSBSim %s, %.1f kg", model.name, model.aircraft, self.sim.mass)
        else:
            self.log.info(
                "vehicle %s: %d rotors, %.3f kg, hover thrust fraction %.3f",
                model.name,
                model.rotor_count,
                model.mass,
                model.hover_thrust_fraction,
            )

    def _wind_params(self) -> WindParams:
        p = self.params
        speed, gust = float(p["SIM_WIND_SPD"]), float(p["SIM_WIND_GUST"])
        return WindParams.from_speed_direction(
            speed,
            float(p["SIM_WIND_DIR"]),
            gust_std_horizontal=gust,
            gust_std_vertical=0.5 * gust,
            gust_time_constant=float(p["SIM_WIND_GUST_T"]),
            enabled=speed > 0.0 or gust > 0.0,
            reference_height=float(p["SIM_WIND_HREF"]),
        )

    def on_params_changed(self, changed: set[str]) -> None:
        if "SIM_GPS_USED" in changed:
            enabled = int(self.params["SIM_GPS_USED"]) >= 4
            self.sim.set_gps_enabled(enabled)
            self.log.info("GPS %s", "restored" if enabled else "lost (fewer than 4 satellites)")
        if changed & {"SIM_WIND_SPD", "SIM_WIND_DIR", "SIM_WIND_GUST", "SIM_WIND_GUST_T", "SIM_WIND_HREF"}:
            self.sim.set_wind(self._wind_params())
        if changed & {p.name for p in battery.PARAMS}:
            self.battery.set_params(self.params.values())
        if self.takeover is not None and changed & {p.name for p in command_loss.PARAMS}:
            self.takeover.set_params(self.params.values())

    def step_period_us(self) -> int:
        return self.sim.imu_period_us

    def _inject_failures(self) -> None:
        """PX4's ``failure`` command (MAV_CMD_INJECT_FAILURE) as the simulated sensors implement it: GPS off/ok."""
        for cmd in self.take(ORB_ID.vehicle_command):
            if cmd.command != VehicleCommand.VEHICLE_CMD_INJECT_FAILURE or not addressed_to(
                cmd, int(self.params["MAV_SYS_ID"]), int(self.params["MAV_COMP_ID"])
            ):
                continue
            if not self.params["SYS_FAILURE_EN"]:
                self.log.warning("failure injection ignored: SYS_FAILURE_EN is 0 (the commander denies it)")
                continue
            unit, kind = cmd.param1, cmd.param2
            if unit != VehicleCommand.FAILURE_UNIT_SENSOR_GPS or kind not in (
                VehicleCommand.FAILURE_TYPE_OK,
                VehicleCommand.FAILURE_TYPE_OFF,
            ):
                self.log.warning("failure injection unit %g type %g is not simulated (only GPS off/ok)", unit, kind)
                continue
            enabled = kind == VehicleCommand.FAILURE_TYPE_OK
            self.sim.set_gps_enabled(enabled)
            self.log.info("GPS %s (failure injection)", "restored" if enabled else "off")

    def _stack_arming(self) -> ActuatorArmed | None:
        """The stack's last ``actuator_armed`` (None: none yet), taken as disarmed until the stack has said disarmed
        once since this plant started. A plant started while the stack says armed (its host lost in a flight and
        started again: a new vehicle, on the ground) keeps its motors stopped until the stack disarms, as a Pixhawk
        powers up disarmed whatever its companion streams; else the stack's loops, flying the vehicle they knew,
        throw the new one about."""
        armed = self.latest(ORB_ID.actuator_armed)
        if armed is None or self._stack_disarmed_seen:
            return armed
        if not armed.armed:
            self._stack_disarmed_seen = True
            return armed
        if not self._said_armed_before:
            self._said_armed_before = True
            self.log.warning("the stack was armed before this plant started: its motors stay stopped until it disarms")
        return ActuatorArmed(timestamp=armed.timestamp, armed=False)

    def motor_commands(self) -> tuple[float, ...]:
        outputs = self.latest(ORB_ID.actuator_outputs_sim)
        armed = self._stack_arming()
        # As PX4's output drivers do, the motors stop on disarm, lockdown, kill or termination whatever the last
        # output said: a dead allocator cannot keep them turning.
        stopped = armed is not None and (not armed.armed or armed.lockdown or armed.kill or armed.termination)
        if outputs is None or stopped:
            commands = (0.0,) * self.input_count
        else:
            commands = tuple(c if math.isfinite(c) else 0.0 for c in outputs.output[: self.input_count])
        takeover = self.takeover
        if takeover is None:
            return commands
        arrived = self.update(ORB_ID.actuator_outputs_sim) is not None
        commands = takeover.motor_commands(self.sim.time_us, arrived, armed, self.truth, self.imu, commands)
        if takeover.events:
            for level, text in takeover.take_events():
                self.log.log(level, text)
        return commands

    def run(self, msg: object, dt: float) -> None:
        now = self.now_us()
        period = self.sim.imu_period_us
        if self.epoch_us is None:
            # Simulated sample times map onto the stack's clock: identical in lockstep, wall time otherwise.
            self.epoch_us = now - (self.sim.time_us + period)
        # Steps due by now: one in lockstep, where each run is one step; more on the wall clock after a late run.
        due = (now - self.epoch_us - self.sim.time_us) // period
        if due > MAX_CATCH_UP_STEPS:
            self.epoch_us += (due - 1) * period
            self.skipped_steps += due - 1
            due = 1
        elif due > 1:
            self.catch_up_steps += due - 1
        self._inject_failures()
        for _ in range(due):
            self._step()

    def status(self) -> dict[str, float | int | str | bool]:
        """Real time: steps run late back to back, and steps skipped (more than MAX_CATCH_UP_STEPS late); a
        multicopter's motor control: the stack's, or the plant's failsafe and its mode, or the plant disarmed."""
        status: dict[str, float | int | str | bool] = {
            "catch_up_steps": self.catch_up_steps,
            "skipped_steps": self.skipped_steps,
        }
        if self.takeover is not None:
            status.update(self.takeover.status())
        return status

    def _step(self) -> None:
        epoch = self.epoch_us
        assert epoch is not None
        for sample in self.sim.advance(self.motor_commands()):
            if isinstance(sample, ImuSample):
                self.imu = sample
                self._publish_imu(sample, epoch)
            elif isinstance(sample, MagSample):
                self._publish_mag(sample, epoch)
            elif isinstance(sample, BaroSample):
                self._publish_baro(sample, epoch)
            elif isinstance(sample, GpsSample):
                self._publish_gps(sample, epoch)
            elif isinstance(sample, AirspeedSample):
                self._publish_airspeed(sample, epoch)
        self.truth = self.sim.truth()
        self._publish_truth(epoch)
        if self.sim.time_us >= self._battery_due_us:
            self._battery_due_us = self.sim.time_us + battery.PERIOD_US
            self._publish_battery(epoch)

    def _publish_imu(self, s: ImuSample, epoch: int) -> None:
        t = epoch + s.time_us
        a, g = s.accel, s.gyro
        self.publish(
            ORB_ID.sensor_accel,
            SensorAccel(timestamp_sample=t, device_id=IMU_DEVICE_ID, x=a[0], y=a[1], z=a[2], temperature=s.temperature),
        )
        self.publish(
            ORB_ID.sensor_gyro,
            SensorGyro(timestamp_sample=t, device_id=IMU_DEVICE_ID, x=g[0], y=g[1], z=g[2], temperature=s.temperature),
        )

    def _publish_mag(self, s: MagSample, epoch: int) -> None:
        f = s.field
        self.publish(
            ORB_ID.sensor_mag,
            SensorMag(timestamp_sample=epoch + s.time_us, device_id=MAG_DEVICE_ID, x=f[0], y=f[1], z=f[2]),
        )

    def _publish_baro(self, s: BaroSample, epoch: int) -> None:
        self.publish(
            ORB_ID.sensor_baro,
            SensorBaro(
                timestamp_sample=epoch + s.time_us,
                device_id=BARO_DEVICE_ID,
                pressure=s.pressure_pa,
                temperature=s.temperature,
            ),
        )

    def _publish_gps(self, s: GpsSample, epoch: int) -> None:
        vn, ve, vd = s.vel_ned
        self.publish(
            ORB_ID.sensor_gps,
            SensorGps(
                timestamp_sample=epoch + s.time_us,
                device_id=GPS_DEVICE_ID,
                latitude_deg=s.lat,
                longitude_deg=s.lon,
                altitude_msl_m=s.alt_msl,
                altitude_ellipsoid_m=s.alt_msl,
                s_variance_m_s=s.s_variance_m_s,
                fix_type=s.fix_type,
                eph=s.eph,
                epv=s.epv,
                hdop=s.hdop,
                vdop=s.vdop,
                vel_m_s=math.hypot(vn, ve),
                vel_n_m_s=vn,
                vel_e_m_s=ve,
                vel_d_m_s=vd,
                cog_rad=math.atan2(ve, vn),
                vel_ned_valid=s.fix_type >= SensorGps.FIX_TYPE_3D,
                satellites_used=s.satellites,
            ),
        )

    def _publish_airspeed(self, s: AirspeedSample, epoch: int) -> None:
        self.publish(
            ORB_ID.airspeed,
            Airspeed(
                timestamp_sample=epoch + s.time_us,
                device_id=AIRSPEED_DEVICE_ID,
                indicated_airspeed_m_s=s.indicated_airspeed,
                true_airspeed_m_s=s.true_airspeed,
                differential_pressure_pa=s.differential_pressure,
                air_temperature_celsius=s.temperature,
                confidence=1.0,
            ),
        )

    def _publish_battery(self, epoch: int) -> None:
        armed = self._stack_arming()
        state = self.battery.update(battery.PERIOD_US * 1e-6, armed is not None and armed.armed)
        self.publish(ORB_ID.battery_status, BatteryStatus(**state._asdict()))

    def _publish_truth(self, epoch: int) -> None:
        t = self.truth
        wind: Vec3 = self.sim.wind
        self.publish(
            ORB_ID.sim_groundtruth,
            SimGroundtruth(
                timestamp_sample=epoch + t.time_us,
                position=t.position,
                velocity=t.velocity,
                acceleration=t.acceleration,
                q=t.q,
                angular_velocity=t.angular_velocity,
                angular_acceleration=t.angular_acceleration,
                lat=t.lat,
                lon=t.lon,
                alt=t.alt,
                on_ground=t.on_ground,
                wind=wind,
                motors=t.motors,
            ),
        )


def _jsbsim_plant():
    from stack.sim.jsbsim_plant import JsbsimPlant  # JSBSim loads only for a vehicle that needs it

    return JsbsimPlant
