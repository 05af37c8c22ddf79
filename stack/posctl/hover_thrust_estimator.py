"""Hover-thrust estimation from vertical acceleration and collective thrust (PX4 mc_hover_thrust_estimator).

Follows ``src/modules/mc_hover_thrust_estimator/zero_order_hover_thrust_ekf.cpp`` and the gating and
validity logic of ``MulticopterHoverThrustEstimator.cpp``. The single state is the hover thrust Th,
modelled as a random walk; the measurement is the upward acceleration, predicted from the upward
collective thrust T as a = g·T/Th − g (so H = −g·T/Th²). The measurement noise is learnt from the
de-biased residuals, innovations beyond the gate are rejected, and a sustained one-sided rejection
inflates the state variance so a real change of hover thrust (payload) is picked up again.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet

_G = CONSTANTS_ONE_G

_ACC_VAR_INIT = 5.0
_ACC_VAR_MIN = 1.0
_ACC_VAR_MAX = 400.0
_STATE_VAR_MIN = 1e-10
_STATE_VAR_MAX = 1.0
_LARGE_OFFSET_TEST_RATIO = 0.2
_BUMP_FACTOR = 1e3
_LPF_TIME_CONSTANT = 1.0
_NOISE_LEARNING_TIME_CONSTANT = 2.0
_VALID_VARIANCE = 0.001
_VALID_HYSTERESIS_US = 2_000_000
_DT_MIN = 0.001
_DT_MAX = 1.0


class HoverThrustEstimatorParams(ParamSet):
    """Tunables of the estimator (the catalogue's): MPC_THR_HOVER, where the estimate starts and the centre of its
    range, and the HTE_* noise, gates and range."""

    mpc_thr_hover: float
    hte_ht_noise: float
    hte_acc_gate: float
    hte_ht_err_init: float
    hte_vxy_thr: float
    hte_vz_thr: float
    hte_thr_range: float


class HoverThrustEstimate(NamedTuple):
    """PX4 ``hover_thrust_estimate``; all NaN (and not valid) while the estimator is not running."""

    hover_thrust: float
    hover_thrust_var: float
    accel_innov: float
    accel_innov_var: float
    accel_innov_test_ratio: float
    accel_noise_var: float
    valid: bool


_INVALID = HoverThrustEstimate(math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, False)


class ZeroOrderHoverThrustEkf:
    """The single-state Kalman filter (PX4 ``ZeroOrderHoverThrustEkf``), thrust positive up."""

    __slots__ = (
        "_acc_var",
        "_acc_var_scale",
        "_dt",
        "_gate_size",
        "_hover_thr_max",
        "_hover_thr_min",
        "_process_var",
        "_residual_lpf",
        "_signed_test_ratio_lpf",
        "hover_thrust",
        "innov",
        "innov_test_ratio",
        "innov_var",
        "state_var",
    )

    def __init__(self, hover_thrust: float = 0.5) -> None:
        self._hover_thr_min = 0.1
        self._hover_thr_max = 0.9
        self._gate_size = 3.0
        self._process_var = 12.5e-6
        self._acc_var = _ACC_VAR_INIT
        self._acc_var_scale = 1.0
        self._dt = 0.02
        self._residual_lpf = 0.0
        self._signed_test_ratio_lpf = 0.0
        self.state_var = 0.01
        self.innov = 0.0
        self.innov_var = 0.0
        self.innov_test_ratio = 0.0
        self.hover_thrust = 0.5
        self.set_hover_thrust(hover_thrust)

    @property
    def accel_noise_var(self) -> float:
        return self._acc_var

    def set_hover_thrust(self, hover_thrust: float) -> None:
        self.hover_thrust = min(max(hover_thrust, self._hover_thr_min), self._hover_thr_max)

    def set_hover_thrust_range(self, minimum: float, maximum: float) -> None:
        self._hover_thr_min = minimum
        self._hover_thr_max = maximum

    def set_hover_thrust_std_dev(self, std_dev: float) -> None:
        self.state_var = std_dev * std_dev

    def set_process_noise_std_dev(self, std_dev: float) -> None:
        self._process_var = std_dev * std_dev

    def set_measurement_noise_scale(self, scale: float) -> None:
        self._acc_var_scale = scale * scale

    def set_accel_innov_gate(self, gate: float) -> None:
        self._gate_size = gate

    def reset_accel_noise(self) -> None:
        self._acc_var = _ACC_VAR_INIT

    def predict(self, dt: float) -> None:
        """Random-walk prediction: only the variance grows."""
        self.state_var += self._process_var * dt * dt
        self._dt = dt

    def fuse_acc_z(self, acc_z: float, thrust: float) -> None:
        """Fuse one upward acceleration [m/s²] measured with upward collective thrust [normalised]."""
        th = self.hover_thrust
        h = -_G * thrust / (th * th)
        r = self._acc_var * self._acc_var_scale
        innov_var = max(h * self.state_var * h + r, r)
        innov = acc_z - (_G * thrust / th - _G)
        gain = self.state_var * h / innov_var
        test_ratio = innov * innov / (self._gate_size * self._gate_size * innov_var)

        residual = innov
        if test_ratio < 1.0:
            self.hover_thrust = min(max(th + gain * innov, self._hover_thr_min), self._hover_thr_max)
            self.state_var = min(max((1.0 - gain * h) * self.state_var, _STATE_VAR_MIN), _STATE_VAR_MAX)
            residual = acc_z - (_G * thrust / self.hover_thrust - _G)
        elif abs(self._signed_test_ratio_lpf) > _LARGE_OFFSET_TEST_RATIO:
            # Measurements rejected on one side for a while: the hover thrust really changed.
            self.state_var += _BUMP_FACTOR * self._process_var * self._dt * self._dt

        dt = self._dt
        alpha = dt / (_LPF_TIME_CONSTANT + dt)
        signed_ratio = min(max(math.copysign(test_ratio, innov), -1.0), 1.0) if innov != 0.0 else 0.0
        self._residual_lpf += alpha * (residual - self._residual_lpf)
        self._signed_test_ratio_lpf += alpha * (signed_ratio - self._signed_test_ratio_lpf)

        alpha = dt / (_NOISE_LEARNING_TIME_CONSTANT + dt)
        unbiased = residual - self._residual_lpf
        acc_var = (1.0 - alpha) * self._acc_var + alpha * (unbiased * unbiased + h * self.state_var * h)
        self._acc_var = min(max(acc_var, _ACC_VAR_MIN), _ACC_VAR_MAX)

        self.innov = innov
        self.innov_var = innov_var
        self.innov_test_ratio = test_ratio


class HoverThrustEstimator:
    """PX4's hover-thrust estimator with its run conditions and validity logic.

    ``update`` is called once per local-position sample with the latest collective thrust
    setpoint. It only estimates while armed, in air and with a sane dt; measurements taken while
    moving faster than HTE_VXY_THR / HTE_VZ_THR are de-weighted (noise scaled by 1 + excess speed).
    The estimate is bounded to MPC_THR_HOVER ± HTE_THR_RANGE within [0.1, 0.9], reset to
    MPC_THR_HOVER while disarmed, and valid once its variance is below 0.001 (with a passing
    innovation test) for 2 s.
    """

    __slots__ = ("_ekf", "_params", "_timestamp_last_us", "_valid", "_valid_since_us")

    def __init__(self, params: HoverThrustEstimatorParams | None = None) -> None:
        self._ekf = ZeroOrderHoverThrustEkf()
        self._timestamp_last_us = 0
        self._valid = False
        self._valid_since_us: int | None = None
        self._params = params or HoverThrustEstimatorParams()
        self._apply_params()
        self.reset()

    @property
    def ekf(self) -> ZeroOrderHoverThrustEkf:
        return self._ekf

    @property
    def hover_thrust(self) -> float:
        return self._ekf.hover_thrust

    @property
    def valid(self) -> bool:
        return self._valid

    def set_params(self, params: HoverThrustEstimatorParams) -> None:
        """Apply new parameters; a changed HTE_HT_ERR_INIT also resets the estimate's variance."""
        if params.hte_ht_err_init != self._params.hte_ht_err_init:
            self._ekf.set_hover_thrust_std_dev(params.hte_ht_err_init)
        self._params = params
        self._apply_params()

    def _apply_params(self) -> None:
        params = self._params
        ekf = self._ekf
        ekf.set_process_noise_std_dev(params.hte_ht_noise)
        ekf.set_accel_innov_gate(params.hte_acc_gate)
        hover = params.mpc_thr_hover
        ekf.set_hover_thrust_range(
            max(min(hover - params.hte_thr_range, 0.8), 0.1),
            min(max(hover + params.hte_thr_range, 0.2), 0.9),
        )

    def reset(self) -> None:
        """Back to MPC_THR_HOVER with the initial uncertainty and noise level."""
        self._ekf.set_hover_thrust(self._params.mpc_thr_hover)
        self._ekf.set_hover_thrust_std_dev(self._params.hte_ht_err_init)
        self._ekf.reset_accel_noise()

    def update(
        self,
        timestamp_us: int,
        *,
        armed: bool,
        in_air: bool,
        velocity: Vec3,
        acc_z: float,
        thrust_z: float,
    ) -> HoverThrustEstimate:
        """Process one sample; all vectors NED.

        acc_z: measured vertical acceleration [m/s², NED, + down]; thrust_z: z component of the
        normalised NED thrust setpoint (negative when lifting). Returns the estimate (all-NaN while
        not estimating).
        """
        dt = (timestamp_us - self._timestamp_last_us) * 1e-6
        self._timestamp_last_us = timestamp_us
        if not (armed and in_air and _DT_MIN < dt < _DT_MAX and math.isfinite(acc_z)):
            self._set_valid(False, timestamp_us)
            if not armed:
                self.reset()
            return _INVALID
        ekf = self._ekf
        ekf.predict(dt)
        if not math.isfinite(thrust_z):
            return self._estimate()

        p = self._params
        noise_z = max(abs(velocity[2]) - p.hte_vz_thr + 1.0, 1.0)
        noise_xy = max(math.hypot(velocity[0], velocity[1]) - p.hte_vxy_thr + 1.0, 1.0)
        ekf.set_measurement_noise_scale(max(noise_xy, noise_z))
        ekf.fuse_acc_z(-acc_z, -thrust_z)

        valid = ekf.state_var < _VALID_VARIANCE
        if not self._valid:
            valid = valid and ekf.innov_test_ratio < 1.0
        self._set_valid(valid, timestamp_us)
        return self._estimate()

    def _set_valid(self, requested: bool, timestamp_us: int) -> None:
        # Becoming valid needs the condition to hold for 2 s; losing validity is immediate.
        if not requested:
            self._valid = False
            self._valid_since_us = None
            return
        if self._valid_since_us is None:
            self._valid_since_us = timestamp_us
        if timestamp_us - self._valid_since_us >= _VALID_HYSTERESIS_US:
            self._valid = True

    def _estimate(self) -> HoverThrustEstimate:
        ekf = self._ekf
        return HoverThrustEstimate(
            ekf.hover_thrust,
            ekf.state_var,
            ekf.innov,
            ekf.innov_var,
            ekf.innov_test_ratio,
            ekf.accel_noise_var,
            self._valid,
        )
