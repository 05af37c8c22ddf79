"""airspeed_selector: checks the airspeed sensor and estimates the wind (PX4 ``src/modules/airspeed_selector``).

At 10 Hz: each new ``airspeed`` sample goes through :class:`stack.fw.airspeed_validator.AirspeedValidator`
(its wind estimator fuses it in fixed-wing flight with ``vehicle_local_position`` and
``vehicle_attitude``, unless that velocity comes from dead reckoning); then ``airspeed_validated`` (IAS,
CAS, TAS of the sensor while valid, NaN otherwise, and ground speed minus wind) and ``wind`` (NaN until the
estimator has started) are published. One sensor (PX4's ASPD_PRIMARY 1), no scale applied, no
ground-minus-wind fallback.

Fixed-wing flight, for the checks and the wind estimate: not landed, the current setpoint not a
landing, and past the takeoff run (the airspeed once above FW_AIRSPD_STALL since the last landing).
"""

from __future__ import annotations

import math

from stack.fw.airspeed_validator import APPLIED_SCALE, AirspeedValidator, AirspeedValidatorParams
from stack.mathlib.quaternion import IDENTITY, is_finite, rotate_inv
from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.msg.fixedwing import AirspeedValidated, PositionSetpoint, Wind
from stack.msg.registry import ORB_ID
from stack.runtime.module import Module, Timer
from stack.runtime.priority import NAV_AND_CONTROLLERS

RATE_HZ = 10.0
LOCAL_POSITION_TIMEOUT_US = 1_000_000
SENSOR_INDEX = 1
"""PX4's index of the first airspeed sensor (-1: none valid)."""
WIND_SOURCE_SENSOR_1 = 1
"""PX4 ``airspeed_wind.source``: the estimator of the first airspeed sensor."""


class AirspeedSelectorModule(Module):
    NAME = "airspeed_selector"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Airspeed checks and wind estimation (PX4 airspeed_selector)"
    TRIGGER = Timer(RATE_HZ)
    DT_RANGE = (0.01, 1.0)
    PARAMS = AirspeedValidatorParams.PARAMS
    PUBLISHES = (ORB_ID.airspeed_validated, ORB_ID.wind)

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.airspeed,
            ORB_ID.vehicle_local_position,
            ORB_ID.vehicle_attitude,
            ORB_ID.vehicle_land_detected,
            ORB_ID.position_setpoint_triplet,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        self.validator = AirspeedValidator(AirspeedValidatorParams.from_params(self.params))
        self.in_takeoff_situation = True

    def on_params_changed(self, changed: set[str]) -> None:
        self.validator.set_params(AirspeedValidatorParams.from_params(self.params))

    def run(self, msg: object, dt: float) -> None:
        now = self.now_us()
        lpos = self.latest(ORB_ID.vehicle_local_position)
        attitude = self.latest(ORB_ID.vehicle_attitude)
        q = attitude.q if attitude is not None and is_finite(attitude.q) else IDENTITY
        velocity = None
        if (
            lpos is not None
            and lpos.v_xy_valid
            and not lpos.dead_reckoning  # the velocity then comes from this wind estimate: it would learn itself
            and now - lpos.timestamp_sample < LOCAL_POSITION_TIMEOUT_US
            and all(math.isfinite(v) for v in (lpos.vx, lpos.vy, lpos.vz))
        ):
            velocity = (lpos.vx, lpos.vy, lpos.vz)
        sample = self.update(ORB_ID.airspeed)
        if sample is not None:
            in_fixed_wing_flight = self._in_fixed_wing_flight(sample.indicated_airspeed_m_s)
            evh = lpos.evh if lpos is not None and math.isfinite(lpos.evh) else 1.0
            self.validator.update(
                now,
                sample.indicated_airspeed_m_s,
                sample.true_airspeed_m_s,
                in_fixed_wing_flight=in_fixed_wing_flight,
                velocity=velocity,
                velocity_var_ne=evh * evh,
                q=q,
                accel_z=self._body_accel_z(lpos, q),
            )
        self.validator.check_timeout(now)
        self._publish(now, velocity)

    def _in_fixed_wing_flight(self, indicated_airspeed: float) -> bool:
        land = self.latest(ORB_ID.vehicle_land_detected)
        triplet = self.latest(ORB_ID.position_setpoint_triplet)
        landing = (
            triplet is not None
            and triplet.current.valid
            and triplet.current.type == PositionSetpoint.SETPOINT_TYPE_LAND
        )
        in_air = land is not None and not land.landed and not landing
        if not in_air:
            self.in_takeoff_situation = True
        elif indicated_airspeed > self.validator.params.fw_airspd_stall:
            self.in_takeoff_situation = False
        return in_air and not self.in_takeoff_situation

    @staticmethod
    def _body_accel_z(lpos, q) -> float:
        """The body-z specific force [m/s²] from the estimator's NED acceleration (−g in level flight)."""
        if lpos is None:
            return math.nan
        return rotate_inv(q, (lpos.ax, lpos.ay, lpos.az - CONSTANTS_ONE_G))[2]

    def _publish(self, now: int, velocity) -> None:
        validator = self.validator
        estimator = validator.wind_estimator
        wind_valid = estimator.initialised
        wind_n, wind_e = estimator.wind if wind_valid else (math.nan, math.nan)
        ground_minus_wind_tas = math.nan
        if velocity is not None and wind_valid:
            air = (velocity[0] - wind_n, velocity[1] - wind_e, velocity[2])
            ground_minus_wind_tas = math.sqrt(air[0] ** 2 + air[1] ** 2 + air[2] ** 2)
        valid = validator.valid and math.isfinite(validator.indicated_airspeed)
        self.publish(
            ORB_ID.airspeed_validated,
            AirspeedValidated(
                timestamp_sample=now,
                indicated_airspeed_m_s=validator.indicated_airspeed if valid else math.nan,
                calibrated_airspeed_m_s=validator.calibrated_airspeed if valid else math.nan,
                true_airspeed_m_s=validator.true_airspeed if valid else math.nan,
                calibrated_ground_minus_wind_m_s=ground_minus_wind_tas / validator.eas_to_tas,
                true_ground_minus_wind_m_s=ground_minus_wind_tas,
                airspeed_sensor_measurement_valid=valid,
                selected_airspeed_index=SENSOR_INDEX if valid else -1,
            ),
        )
        var_n, var_e = estimator.wind_variance if wind_valid else (math.nan, math.nan)
        self.publish(
            ORB_ID.wind,
            Wind(
                timestamp_sample=now,
                windspeed_north=wind_n,
                windspeed_east=wind_e,
                variance_north=var_n,
                variance_east=var_e,
                tas_innov=estimator.tas_innov,
                tas_innov_var=estimator.tas_innov_var,
                tas_scale_raw=estimator.tas_scale,
                tas_scale_validated=APPLIED_SCALE,
                source=WIND_SOURCE_SENSOR_1,
            ),
        )
