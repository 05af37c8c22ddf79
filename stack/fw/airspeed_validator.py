"""Airspeed checks for one sensor (PX4 v1.13 ``src/modules/airspeed_selector/AirspeedValidator.cpp``).

Each new sample feeds the wind estimator (in fixed-wing flight, with a valid ground velocity) and
runs the checks:

- data missing: no sample for 1 s makes the airspeed invalid at once;
- innovation: the estimator's test ratio innov²/(gate²·var) above ASPD_FS_INNOV is integrated; once the
  integral passes ASPD_FS_INTEG [s] (≤ 0: any exceedance) for 1 s, the check fails;
- load factor: a measured load factor the airspeed could not lift (n > 1.1·(CAS/FW_AIRSPD_STALL)²,
  low-pass filtered) fails the check.

A failed check invalidates the airspeed after ASPD_FS_T_STOP seconds (both at once: immediately);
with all checks passing for ASPD_FS_T_START seconds it is valid again (negative: never, in this run).
The innovation and load factor checks run only with ASPD_DO_CHECKS and in fixed-wing flight (in the
air, not landing, after the takeoff run has passed the stall speed), and the innovation check not in
the first 10 s after the estimator (re)started.
"""

from __future__ import annotations

import math

from stack.fw.wind_estimator import WindEstimator, WindEstimatorParams
from stack.mathlib.quaternion import Quat
from stack.mathlib.scalar import CONSTANTS_ONE_G, constrain
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet

APPLIED_SCALE = 1.0
"""CAS = IAS·scale: no scale is applied (PX4's default ASPD_SCALE 1, no scale estimate applied)."""
DATA_TIMEOUT_US = 1_000_000
TAS_INNOV_FAIL_DELAY_US = 1_000_000
WIND_ESTIMATOR_SETTLE_US = 10_000_000
LOAD_FACTOR_RATIO_MAX = 1.1
LOAD_FACTOR_FILTER = 0.05
"""Weight of each new sample in the load factor ratio's low-pass filter (PX4: 0.05 per sample)."""


class AirspeedValidatorParams(ParamSet):
    """The checks' settings (the catalogue's): ASPD_FS_INNOV, the test ratio above which innovations count;
    ASPD_FS_INTEG [s]; ASPD_FS_T_STOP and ASPD_FS_T_START [s] (negative: never valid again); FW_AIRSPD_STALL;
    and the wind estimator's."""

    aspd_do_checks: int
    aspd_fs_innov: float
    aspd_fs_integ: float
    aspd_fs_t_stop: int
    aspd_fs_t_start: int
    fw_airspd_stall: float
    wind: WindEstimatorParams


class AirspeedValidator:
    """The checks and the wind estimator of one airspeed sensor."""

    def __init__(self, params: AirspeedValidatorParams) -> None:
        self.params = params
        self.wind_estimator = WindEstimator(params.wind)
        self.valid = True
        self.indicated_airspeed = math.nan
        self.calibrated_airspeed = math.nan
        self.true_airspeed = math.nan
        self.eas_to_tas = 1.0
        self.innovations_check_failed = False
        self.load_factor_check_failed = False
        self.load_factor_ratio = 0.5
        self._innov_integral = 0.0
        self._time_last_sample_us: int | None = None
        self._time_last_innov_check_us = 0
        self._time_last_tas_pass_us = 0
        self._time_checks_passed_us = 0
        self._time_checks_failed_us = 0
        self._time_estimator_started_us = 0

    def set_params(self, params: AirspeedValidatorParams) -> None:
        self.params = params
        self.wind_estimator.set_params(params.wind)

    def update(
        self,
        time_us: int,
        indicated_airspeed: float,
        true_airspeed: float,
        *,
        in_fixed_wing_flight: bool,
        velocity: Vec3 | None,
        velocity_var_ne: float,
        q: Quat,
        accel_z: float,
    ) -> None:
        """One new sample: IAS and the sensor's TAS [m/s]; ``velocity`` the NED ground velocity (None: not
        valid) with its horizontal variance; ``accel_z`` the body-z specific force [m/s²]."""
        if not (math.isfinite(indicated_airspeed) and math.isfinite(true_airspeed)):
            return
        self._time_last_sample_us = time_us
        self.indicated_airspeed = indicated_airspeed
        if indicated_airspeed > 0.0 and true_airspeed > 0.0:
            # The sensor's own density correction (its driver's TAS from IAS, pressure and temperature).
            self.eas_to_tas = true_airspeed / indicated_airspeed
        self.calibrated_airspeed = indicated_airspeed * APPLIED_SCALE
        self.true_airspeed = self.calibrated_airspeed * self.eas_to_tas

        estimator = self.wind_estimator
        estimator.update(time_us)
        if velocity is not None and in_fixed_wing_flight:
            estimator.fuse_airspeed(time_us, true_airspeed, velocity, velocity_var_ne, q)
            estimator.fuse_beta(time_us, velocity, velocity_var_ne, q)
        checks = bool(self.params.aspd_do_checks) and in_fixed_wing_flight
        self._check_innovation(time_us, checks)
        self._check_load_factor(checks, accel_z)
        self._update_valid(time_us)

    def check_timeout(self, time_us: int) -> None:
        """No sample for ``DATA_TIMEOUT_US`` (once data has come): invalid at once."""
        last = self._time_last_sample_us
        if last is not None and time_us - last > DATA_TIMEOUT_US:
            self.valid = False
            self._time_checks_failed_us = time_us

    def _check_innovation(self, time_us: int, enabled: bool) -> None:
        p = self.params
        estimator = self.wind_estimator
        if estimator.reset_this_step:
            self._time_estimator_started_us = time_us
        if not enabled or time_us - self._time_estimator_started_us < WIND_ESTIMATOR_SETTLE_US:
            self.innovations_check_failed = False
            self._time_last_tas_pass_us = time_us
            self._innov_integral = 0.0
        else:
            dt = constrain((time_us - self._time_last_innov_check_us) * 1e-6, 0.01, 0.2)
            gate = max(p.wind.aspd_tas_gate, 1.0)
            innov_var = estimator.tas_innov_var
            test_ratio = estimator.tas_innov**2 / (gate * gate * innov_var) if innov_var > 0.0 else 0.0
            if test_ratio > p.aspd_fs_innov:
                self._innov_integral += dt * (test_ratio - p.aspd_fs_innov)
            else:
                self._innov_integral = 0.0
                if p.aspd_fs_integ <= 0.0:
                    self._time_last_tas_pass_us = time_us
            if p.aspd_fs_integ > 0.0 and self._innov_integral < p.aspd_fs_integ:
                self._time_last_tas_pass_us = time_us
            self.innovations_check_failed = time_us - self._time_last_tas_pass_us > TAS_INNOV_FAIL_DELAY_US
        self._time_last_innov_check_us = time_us

    def _check_load_factor(self, enabled: bool, accel_z: float) -> None:
        if not enabled or not math.isfinite(accel_z):
            self.load_factor_ratio = 0.5
            self.load_factor_check_failed = False
            return
        max_lift_ratio = (max(self.calibrated_airspeed, 0.7) / max(self.params.fw_airspd_stall, 1.0)) ** 2
        ratio = abs(accel_z) / CONSTANTS_ONE_G / max_lift_ratio
        self.load_factor_ratio += LOAD_FACTOR_FILTER * (ratio - self.load_factor_ratio)
        self.load_factor_ratio = constrain(self.load_factor_ratio, 0.25, 2.0)
        self.load_factor_check_failed = self.load_factor_ratio > LOAD_FACTOR_RATIO_MAX

    def _update_valid(self, time_us: int) -> None:
        p = self.params
        failed = self.innovations_check_failed or self.load_factor_check_failed
        if failed:
            self._time_checks_failed_us = time_us
        else:
            self._time_checks_passed_us = time_us
        if self.valid:
            # Both failing together is likely a real fault; one alone may be a short false alarm.
            both = self.innovations_check_failed and self.load_factor_check_failed
            if both or time_us - self._time_checks_passed_us > p.aspd_fs_t_stop * 1e6:
                self.valid = False
        elif p.aspd_fs_t_start > 0.0 and time_us - self._time_checks_failed_us > p.aspd_fs_t_start * 1e6:
            self.valid = True
