"""attitude_estimator_q and the gyro pipeline as one module, run on every gyro sample.

It publishes ``vehicle_angular_velocity`` first (the rate loop's input, bias-corrected and
filtered, with the angular acceleration for the D term) and then ``vehicle_attitude``, as PX4's
``sensors`` and ``attitude_estimator_q`` modules do between them; and at 10 Hz
``vehicle_imu_status`` and ``estimator_status``, summaries for the commander, whose checks do not
need every 250 Hz sample.
"""

from __future__ import annotations

import math
from collections import deque

from stack.estimator.acceleration import VelocityDerivative
from stack.estimator.angular_velocity import AngularVelocityFilter, GyroFilterParams
from stack.estimator.attitude_q import AttitudeEstimatorParams, AttitudeEstimatorQ
from stack.estimator.imu_summary import STATUS_INTERVAL_US, ImuSummary
from stack.msg.estimation import EstimatorStatus, VehicleAngularVelocity, VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.sensors import SensorAccel, SensorGyro
from stack.params import catalogue
from stack.params.binding import combine
from stack.runtime.module import TRIGGER_BACKLOG, Module, Trigger
from stack.runtime.priority import INS

ATTITUDE_PARAMS = AttitudeEstimatorParams.PARAMS
COMPENSATION_PARAMS = catalogue.params("ATT_ACC_COMP_LP")


class AttitudeEstimatorModule(Module):
    NAME = "attitude_estimator_q"
    WORK_QUEUE = INS
    DESCRIPTION = "Quaternion complementary filter (PX4 attitude_estimator_q) and gyro filtering"
    TRIGGER = Trigger(ORB_ID.sensor_gyro, every=True)
    DT_RANGE = (0.00001, 0.02)
    PARAMS = combine(ATTITUDE_PARAMS, GyroFilterParams.PARAMS, COMPENSATION_PARAMS)
    PUBLISHES = (
        ORB_ID.vehicle_angular_velocity,
        ORB_ID.vehicle_attitude,
        ORB_ID.vehicle_imu_status,
        ORB_ID.estimator_status,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        self.subscribe(ORB_ID.sensor_accel, queue=True)
        self.subscribe(ORB_ID.sensor_mag)
        self.subscribe(ORB_ID.vehicle_local_position)
        self.subscribe(ORB_ID.sensor_gps)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.imu = ImuSummary()
        self._attitude_time = 0
        self.estimator = AttitudeEstimatorQ(AttitudeEstimatorParams.from_params(self.params))
        self.rates = AngularVelocityFilter(GyroFilterParams.from_params(self.params))
        self.acceleration = VelocityDerivative(float(self.params["ATT_ACC_COMP_LP"]))
        self._accels: deque[SensorAccel] = deque(maxlen=TRIGGER_BACKLOG)
        self._velocity_time = 0
        self._resume(self.kept_state())

    def _resume(self, kept: dict | None) -> None:
        """Restarted after a crash (maybe in flight, where a still-vehicle alignment cannot happen): carry on from
        the attitude and gyro bias the previous instance kept, the accelerometer correcting the tilt."""
        if kept is None:
            return
        q, bias = kept.get("q"), kept.get("gyro_bias")
        valid = isinstance(q, list) and len(q) == 4 and isinstance(bias, list) and len(bias) == 3
        if not valid or not all(isinstance(v, float) and math.isfinite(v) for v in (*q, *bias)):
            self.log.warning("restarted, but the kept attitude is not usable: aligning afresh")
            return
        self.estimator.reset(tuple(q))
        limit = self.estimator.bias_max
        self.estimator.gyro_bias = tuple(max(-limit, min(limit, b)) for b in bias)
        self.log.info("restarted: resuming from the kept attitude")

    def on_params_changed(self, changed: set[str]) -> None:
        self.estimator.set_params(AttitudeEstimatorParams.from_params(self.params))
        self.rates.set_params(GyroFilterParams.from_params(self.params))
        if "ATT_ACC_COMP_LP" in changed:
            self.acceleration = VelocityDerivative(float(self.params["ATT_ACC_COMP_LP"]))

    def run(self, gyro_msg: SensorGyro, dt: float) -> None:
        t = gyro_msg.timestamp_sample
        gyro = (gyro_msg.x, gyro_msg.y, gyro_msg.z)
        accel_msg = self._accel_at(t)
        mag_msg = self.update(ORB_ID.sensor_mag)
        mag = (mag_msg.x, mag_msg.y, mag_msg.z) if mag_msg is not None else None
        if accel_msg is not None:
            accel = (accel_msg.x, accel_msg.y, accel_msg.z)
            self.estimator.update(dt, gyro, accel, mag, self._acceleration_compensation())
        xyz, xyz_dot = self.rates.update(t, gyro, self.estimator.gyro_bias)
        self.imu.add(t, xyz, accel_msg)
        if self.behind():
            return  # a busy machine left a backlog of gyro samples: integrate each, publish the newest only
        self.publish(
            ORB_ID.vehicle_angular_velocity, VehicleAngularVelocity(timestamp_sample=t, xyz=xyz, xyz_derivative=xyz_dot)
        )
        if self.estimator.initialised:
            self.publish(ORB_ID.vehicle_attitude, VehicleAttitude(timestamp_sample=t, q=self.estimator.q))
            self._attitude_time = self.now_us()
            if self.keep_due():
                self.keep_state({"q": list(self.estimator.q), "gyro_bias": list(self.estimator.gyro_bias)})
        if t - self.imu.start_us >= STATUS_INTERVAL_US:
            self._publish_status(gyro_msg)

    def _accel_at(self, t: int) -> SensorAccel | None:
        """The accelerometer sample of gyro sample time ``t`` (the IMU samples both at once), else the newest before
        it. Every gyro sample is integrated: a real-time run working off a backlog of gyro samples (a busy
        machine) meets each with its own accelerometer sample, not the newest one."""
        accels = self._accels
        accels.extend(self.take(ORB_ID.sensor_accel))
        while len(accels) > 1 and accels[1].timestamp_sample <= t:
            accels.popleft()
        return accels[0] if accels else None

    def _publish_status(self, gyro_msg: SensorGyro) -> None:
        now = self.now_us()
        self.publish(ORB_ID.vehicle_imu_status, self.imu.status(gyro_msg))
        self.publish(
            ORB_ID.estimator_status,
            EstimatorStatus(
                attitude_valid=self.estimator.initialised,
                q=self.estimator.q,
                attitude_timestamp=self._attitude_time,
                angular_velocity_timestamp=now,
                gyro_bias=self.estimator.gyro_bias,
            ),
        )

    def _acceleration_compensation(self) -> tuple[float, float, float] | None:
        """NED acceleration from the local-position velocity, or the GPS velocity without one (ATT_ACC_COMP)."""
        if not self.params["ATT_ACC_COMP"]:
            return None
        lpos = self.latest(ORB_ID.vehicle_local_position)
        if lpos is not None and lpos.v_xy_valid and lpos.v_z_valid:
            if lpos.timestamp_sample > self._velocity_time:
                self._velocity_time = lpos.timestamp_sample
                self.acceleration.update(lpos.timestamp_sample, (lpos.vx, lpos.vy, lpos.vz))
            return self.acceleration.acceleration
        gps = self.latest(ORB_ID.sensor_gps)
        if gps is not None and gps.vel_ned_valid and gps.timestamp_sample > self._velocity_time:
            self._velocity_time = gps.timestamp_sample
            self.acceleration.update(gps.timestamp_sample, (gps.vel_n_m_s, gps.vel_e_m_s, gps.vel_d_m_s))
        return self.acceleration.acceleration
