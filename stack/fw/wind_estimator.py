"""Wind and airspeed-scale estimator: a 3-state EKF (PX4 ``src/lib/wind_estimator/WindEstimator.cpp``).

States: the horizontal wind (north, east) [m/s] and the true airspeed scale k (measured TAS =
k·|v − w|, v the NED ground velocity, the wind horizontal). Constant-state model; the covariance grows
once a second by (σ·Δt)² (ASPD_W_P_NOISE for the wind, ASPD_SC_P_NOISE for the scale; PX4 v1.13's
process noise, without its spurious north–east cross term). Two measurements, each fused at most at
10 Hz:

- the true airspeed (noise ASPD_TAS_NOISE), h = k·|v − w|;
- zero sideslip (noise ASPD_BETA_NOISE): β ≈ v_rel,y / v_rel,x with v_rel = Rᵀ·(v − w) in body axes.

An innovation beyond the gate (ASPD_TAS_GATE, ASPD_BETA_GATE standard deviations) is not fused; one
rejected continuously for 5 s restarts the filter. The filter starts from the first airspeed in flight
at the attitude's heading, w = v − TAS·(cos ψ, sin ψ), with the covariance of PX4 v1.14's
``init_wind_using_airspeed`` (heading 10°, sideslip 15° 1-σ uncertainty), which does not assume the
ground track is the heading.
"""

from __future__ import annotations

import math

from stack.mathlib.quaternion import Quat, rotate_inv, to_dcm, yaw
from stack.mathlib.vector import Vec3
from stack.params.binding import ParamSet

PREDICT_PERIOD_US = 1_000_000
FUSE_PERIOD_US = 100_000
REJECT_RESTART_US = 5_000_000
INITIAL_HEADING_VAR = math.radians(10.0) ** 2
INITIAL_SIDESLIP_VAR = math.radians(15.0) ** 2
INITIAL_SCALE_VAR = 1.0e-4
WIND_VAR_MAX = 25.0
SCALE_VAR_MAX = 0.1
VEL_VAR_MIN = 0.01
MIN_FORWARD_AIRSPEED = 0.1
"""Below this body-x air velocity [m/s] the sideslip is undefined and not fused."""



class WindEstimatorParams(ParamSet):
    """Noise and gates (the catalogue's ASPD_*, ``stack/params/airspeed.py``)."""

    aspd_w_p_noise: float
    aspd_sc_p_noise: float
    aspd_tas_noise: float
    aspd_beta_noise: float
    aspd_tas_gate: int
    aspd_beta_gate: int


class WindEstimator:
    """``update`` (covariance prediction) every step, then ``fuse_airspeed`` / ``fuse_beta`` in flight."""

    def __init__(self, params: WindEstimatorParams) -> None:
        self.params = params
        self.initialised = False
        self.reset_this_step = False
        """The filter (re)started during this step (PX4 ``get_wind_estimator_reset``)."""
        self.state = [0.0, 0.0, 1.0]
        self.P: list[list[float]] = [[0.0] * 3 for _ in range(3)]
        self.tas_innov = 0.0
        self.tas_innov_var = 0.0
        self.beta_innov = 0.0
        self.beta_innov_var = 0.0
        self._last_predict_us = 0
        self._last_tas_fuse_us = 0
        self._last_beta_fuse_us = 0
        self._tas_rejected_since_us = 0
        self._beta_rejected_since_us = 0

    def set_params(self, params: WindEstimatorParams) -> None:
        self.params = params

    @property
    def wind(self) -> tuple[float, float]:
        return (self.state[0], self.state[1])

    @property
    def wind_variance(self) -> tuple[float, float]:
        return (self.P[0][0], self.P[1][1])

    @property
    def tas_scale(self) -> float:
        """CAS = IAS·scale: the inverse of the state k, within 0.1…10 (PX4 ``get_tas_scale``)."""
        return 1.0 / min(max(self.state[2], 0.1), 10.0)

    def update(self, time_us: int) -> None:
        """Grow the covariance, once a second."""
        self.reset_this_step = False
        if not self.initialised:
            return
        if self._last_predict_us == 0:
            self._last_predict_us = time_us
            return
        if time_us - self._last_predict_us < PREDICT_PERIOD_US:
            return
        dt = (time_us - self._last_predict_us) * 1e-6
        self._last_predict_us = time_us
        q_wind = (self.params.aspd_w_p_noise * dt) ** 2
        self.P[0][0] += q_wind
        self.P[1][1] += q_wind
        self.P[2][2] += (self.params.aspd_sc_p_noise * dt) ** 2

    def fuse_airspeed(
        self, time_us: int, true_airspeed: float, velocity: Vec3, velocity_var_ne: float, q: Quat
    ) -> None:
        """Fuse a true airspeed [m/s] with the NED ground ``velocity`` (horizontal variance [m²/s²])."""
        if not all(math.isfinite(x) for x in (true_airspeed, velocity_var_ne, *velocity, *q)):
            return
        velocity_var_ne = max(velocity_var_ne, VEL_VAR_MIN)
        if not self.initialised:
            self._initialise(time_us, velocity, velocity_var_ne, yaw(q), true_airspeed)
            return
        if time_us - self._last_tas_fuse_us < FUSE_PERIOD_US:
            return
        self._last_tas_fuse_us = time_us
        wn, we, k = self.state
        rel = (velocity[0] - wn, velocity[1] - we, velocity[2])
        speed = math.sqrt(rel[0] ** 2 + rel[1] ** 2 + rel[2] ** 2)
        if speed < 1e-3:
            return
        h = (-k * rel[0] / speed, -k * rel[1] / speed, speed)
        self.tas_innov = true_airspeed - k * speed
        self.tas_innov_var, ph = self._innovation_variance(h, self.params.aspd_tas_noise**2)
        rejected = self._rejected(self.tas_innov, self.tas_innov_var, self.params.aspd_tas_gate)
        self._tas_rejected_since_us = (self._tas_rejected_since_us or time_us) if rejected else 0
        if self.tas_innov_var <= 0.0 or self._rejected_too_long(time_us, self._tas_rejected_since_us):
            self._initialise(time_us, velocity, velocity_var_ne, yaw(q), true_airspeed)
        elif not rejected:
            self._correct(ph, self.tas_innov, self.tas_innov_var)

    def fuse_beta(self, time_us: int, velocity: Vec3, velocity_var_ne: float, q: Quat) -> None:
        """Fuse zero sideslip: the air flows along the body x-z plane."""
        if not self.initialised or not all(math.isfinite(x) for x in (velocity_var_ne, *velocity, *q)):
            return
        if time_us - self._last_beta_fuse_us < FUSE_PERIOD_US:
            return
        self._last_beta_fuse_us = time_us
        wn, we, _ = self.state
        x, y, _ = rotate_inv(q, (velocity[0] - wn, velocity[1] - we, velocity[2]))
        if abs(x) < MIN_FORWARD_AIRSPEED:
            return
        r = to_dcm(q)  # body → NED: r[i][j] is body axis j's component along NED axis i
        # β ≈ y/x with x = Σ r[i][0]·rel_i, y = Σ r[i][1]·rel_i, rel = v − w.
        h = (-(r[0][1] * x - y * r[0][0]) / (x * x), -(r[1][1] * x - y * r[1][0]) / (x * x), 0.0)
        self.beta_innov = -y / x
        self.beta_innov_var, ph = self._innovation_variance(h, self.params.aspd_beta_noise**2)
        rejected = self._rejected(self.beta_innov, self.beta_innov_var, self.params.aspd_beta_gate)
        self._beta_rejected_since_us = (self._beta_rejected_since_us or time_us) if rejected else 0
        if self.beta_innov_var <= 0.0 or self._rejected_too_long(time_us, self._beta_rejected_since_us):
            speed = math.sqrt(velocity[0] ** 2 + velocity[1] ** 2 + velocity[2] ** 2)
            self._initialise(time_us, velocity, max(velocity_var_ne, VEL_VAR_MIN), yaw(q), speed)
        elif not rejected:
            self._correct(ph, self.beta_innov, self.beta_innov_var)

    # -- internals ---------------------------------------------------------------------------------

    def _innovation_variance(self, h: Vec3, measurement_var: float) -> tuple[float, Vec3]:
        """H·P·Hᵀ + R, and P·Hᵀ."""
        P = self.P
        ph = (
            P[0][0] * h[0] + P[0][1] * h[1] + P[0][2] * h[2],
            P[1][0] * h[0] + P[1][1] * h[1] + P[1][2] * h[2],
            P[2][0] * h[0] + P[2][1] * h[1] + P[2][2] * h[2],
        )
        return h[0] * ph[0] + h[1] * ph[1] + h[2] * ph[2] + measurement_var, ph

    @staticmethod
    def _rejected(innov: float, innov_var: float, gate: float) -> bool:
        return innov * innov > gate * gate * innov_var

    @staticmethod
    def _rejected_too_long(time_us: int, rejected_since_us: int) -> bool:
        return rejected_since_us != 0 and time_us - rejected_since_us > REJECT_RESTART_US

    def _correct(self, ph: Vec3, innov: float, innov_var: float) -> None:
        gain = (ph[0] / innov_var, ph[1] / innov_var, ph[2] / innov_var)
        for i in range(3):
            self.state[i] += gain[i] * innov
        # P ← P − K·H·P, and H·P = (P·Hᵀ)ᵀ since P is symmetric.
        for i in range(3):
            for j in range(3):
                self.P[i][j] -= gain[i] * ph[j]
        self._sanity_checks()

    def _initialise(self, time_us: int, velocity: Vec3, velocity_var_ne: float, heading: float, tas: float) -> None:
        c, s = math.cos(heading), math.sin(heading)
        tas_var = self.params.aspd_tas_noise**2
        tas2 = tas * tas
        lateral_var = tas2 * (INITIAL_SIDESLIP_VAR + INITIAL_HEADING_VAR)
        self.state = [velocity[0] - tas * c, velocity[1] - tas * s, 1.0]
        cross = c * s * (tas_var - lateral_var)
        self.P = [
            [c * c * tas_var + s * s * lateral_var + velocity_var_ne, cross, 0.0],
            [cross, s * s * tas_var + c * c * lateral_var + velocity_var_ne, 0.0],
            [0.0, 0.0, INITIAL_SCALE_VAR],
        ]
        self._tas_rejected_since_us = 0
        self._beta_rejected_since_us = 0
        self._last_predict_us = time_us
        self.initialised = True
        self.reset_this_step = True

    def _sanity_checks(self) -> None:
        P = self.P
        if any(P[i][i] < 0.0 for i in range(3)) or not all(math.isfinite(x) for x in self.state):
            # Ill-conditioned: start again with the next airspeed.
            self.initialised = False
            return
        P[0][0] = min(P[0][0], WIND_VAR_MAX)
        P[1][1] = min(P[1][1], WIND_VAR_MAX)
        P[2][2] = min(P[2][2], SCALE_VAR_MAX)
        self.state[2] = max(self.state[2], 0.0)
        for i in range(3):
            for j in range(i):
                P[i][j] = P[j][i] = 0.5 * (P[i][j] + P[j][i])
