"""Total Energy Control System: pitch and throttle from an altitude and an airspeed demand (PX4 TECS).

Follows ``src/lib/tecs/TECS.cpp`` of PX4 v1.13, with v1.14's underspeed protection (Paul Riseborough's TECS,
after Lambregts, "Vertical flight path and speed control autopilot design using total energy principles",
AIAA 1983). The specific (per unit mass) energies are the potential SPE = g·h and the kinetic SKE = ½·V²;
their rates are SPĖ = g·ḣ and SKĖ = V·V̇ (V the true airspeed).

- Throttle controls the total energy rate STĖ = SPĖ + SKĖ. The demanded rate maps linearly onto
  throttle from the trim throttle: full throttle at STĖ = g·FW_T_CLMB_MAX, minimum throttle at
  STĖ = −g·FW_T_SINK_MIN, plus FW_T_THR_DAMP·(rate error) and an integrator (FW_T_I_GAIN_THR); the
  demand grows in turns by FW_T_RLL2THR·(n − 1) for the load factor n = 1/cos φ.
- Pitch controls the balance rate SEḂ = w_p·SPĖ − w_k·SKĖ (FW_T_SPDWEIGHT sets w_k, and w_p = 2 − w_k,
  each at most 1): θ = (FW_T_SEB_R_FF·SEḂ_sp + FW_T_PTCH_DAMP·(SEḂ error) + integrator) / (g·V).

The demands are shaped first: the altitude setpoint through a jerk-limited trajectory (vertical
acceleration FW_T_VERT_ACC, climb/sink rate FW_T_CLMB_R_SP/FW_T_SINK_R_SP), then
ḣ_sp = (h_ref − h)/FW_T_ALT_TC + FW_T_HRATE_FF·ḣ_ref within −FW_T_SINK_MAX…FW_T_CLMB_MAX; the
airspeed through V̇_sp = (V_sp − V)/FW_T_TAS_TC, limited to half the rate the throttle range can give.
The airspeed is smoothed by a second-order complementary filter with the airspeed rate
(FW_T_SPD_OMEGA); without the estimator's vertical velocity, height and height rate come from
PX4's earlier third-order baro-inertial complementary filter (FW_T_HGT_OMEGA; Widnall and Sinha,
AIAA 78-1307R).

Protections: underspeed (v1.14's ``TECSControl::_detectUnderspeed``: a ratio that ramps from 0 to 1 as the
airspeed falls from the minimum less 15 % of the trim airspeed to the minimum less 30 %; by that ratio the pitch
loop is blended towards speed only, the throttle towards its maximum and the airspeed setpoint towards the
minimum, and the throttle integrator is held), uncommanded descent (v1.13's: large energy deficit while losing
energy at high throttle → minimum airspeed setpoint), and climb-out (v1.13's: full throttle, pitch for speed
only, pitch at least the climb-out minimum). Without an airspeed (NaN) TECS flies
the trim airspeed open loop: pitch controls height alone and throttle is the predicted throttle.

Units: SI, angles in radians, altitude positive up, airspeeds equivalent (EAS) unless named true.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

from stack.mathlib.filters import AlphaFilter
from stack.mathlib.scalar import CONSTANTS_ONE_G, FLT_EPSILON, constrain
from stack.msg.fixedwing import TecsStatus
from stack.params.binding import ParamSet
from stack.posctl.position_smoothing import max_speed_from_distance
from stack.posctl.velocity_smoothing import VelocitySmoothing

G = CONSTANTS_ONE_G
DT_MIN = 0.001
"""Shortest step [s] (PX4 ``DT_MIN``)."""
DT_MAX = 1.0
"""A longer gap than this [s] restarts the filters and integrators (PX4 ``DT_MAX``)."""
DT_DEFAULT = 0.02
"""The step taken after such a gap [s] (PX4 ``DT_DEFAULT``)."""
JERK_MAX = 1000.0
"""Jerk of the altitude trajectory [m/s³]: PX4 wants none, so a large value."""
TAS_STATE_MIN = 3.0
"""Floor of the filtered true airspeed [m/s] (PX4 keeps it off zero for the divisions by V)."""
TAS_ERROR_PERCENTAGE = 0.15
"""The airspeed tracking error expected, as a fraction of the trim airspeed: the underspeed ramp starts that far
below the minimum airspeed and is as wide (PX4 v1.14 TECS.hpp ``tas_error_percentage``)."""
DESCENT_ENERGY_ERROR = 200.0
"""Specific total energy deficit [m²/s²] beyond which a descent at high throttle is uncommanded."""
DESCENT_THROTTLE_RATIO = 0.9
CLIMBOUT_THROTTLE_MARGIN = 0.01
LOAD_FACTOR_COS_MIN = 0.1


class TecsParams(ParamSet):
    """TECS' tunables (the catalogue's, ``stack/params/fw_pos.py`` and ``fw_att.py``)."""

    fw_t_clmb_max: float
    fw_t_sink_min: float
    fw_t_sink_max: float
    fw_t_alt_tc: float
    fw_t_tas_tc: float
    fw_t_thr_damp: float
    fw_t_i_gain_thr: float
    fw_t_i_gain_pit: float
    fw_t_ptch_damp: float
    fw_t_vert_acc: float
    fw_t_hrate_ff: float
    fw_t_spdweight: float
    fw_t_spd_omega: float
    fw_t_hgt_omega: float
    fw_t_rll2thr: float
    fw_t_ste_r_tc: float
    fw_t_tas_r_tc: float
    fw_t_seb_r_ff: float
    fw_t_clmb_r_sp: float
    fw_t_sink_r_sp: float
    fw_airspd_min: float
    fw_airspd_trim: float
    fw_airspd_max: float


class TecsMode(IntEnum):
    """What TECS is doing (PX4 ``ECL_TECS_MODE``)."""

    NORMAL = 0
    UNDERSPEED = 1
    BAD_DESCENT = 2
    CLIMBOUT = 3


class TecsOutput(NamedTuple):
    pitch_sp: float
    """Pitch setpoint [rad], within the limits of the call."""
    throttle_sp: float
    """Throttle setpoint [0, 1], within the limits of the call."""
    mode: TecsMode


class Tecs:
    """PX4's TECS: ``update`` once per position-control step returns the pitch and throttle setpoints.

    It restarts (filters, integrators, trajectory, setpoints from the present state) on its first call,
    after a gap longer than ``DT_MAX``, while not in the air, and after ``reset`` (call it on a change of
    flight mode, as PX4's ``reset_state``).
    """

    def __init__(self, params: TecsParams) -> None:
        self.params = params
        self._initialised = False
        self._mode = TecsMode.NORMAL
        self._alt_trajectory = VelocitySmoothing(max_jerk=JERK_MAX)
        self._tas_rate_filter = AlphaFilter()
        self._ste_rate_error_filter = AlphaFilter()
        # Height: the vertical states (and the baro-inertial filter's acceleration bias state).
        self._vert_pos = 0.0
        self._vert_vel = 0.0
        self._vert_accel = 0.0
        # Airspeed: complementary filter states, the rate measured and filtered.
        self._tas_state = 0.0
        self._tas_rate_state = 0.0
        self._tas_innov = 0.0
        self._tas_rate_raw = 0.0
        self._tas_rate_filtered = 0.0
        # Demands.
        self._eas_setpoint = math.nan
        self._tas_setpoint_adj = 0.0
        self._tas_rate_setpoint = 0.0
        self._tas_min = 0.0
        self._hgt_setpoint_in = math.nan
        self._hgt_setpoint = 0.0
        self._hgt_rate_setpoint = 0.0
        # Energies and their errors.
        self._spe_rate_setpoint = self._ske_rate_setpoint = 0.0
        self._spe_rate = self._ske_rate = 0.0
        self._ste_error = 0.0
        self._ste_rate_error = 0.0
        self._seb_rate_error = 0.0
        self._spe_weighting = self._ske_weighting = 1.0
        # Outputs and integrators.
        self._throttle_integ = 0.0
        self._pitch_integ = 0.0
        self._throttle_setpoint = 0.0
        self._pitch_setpoint = 0.0
        self._pitch_setpoint_unc = 0.0
        self._throttle_trim = math.nan
        self._underspeed_ratio = 0.0
        self._uncommanded_descent = False

    def set_params(self, params: TecsParams) -> None:
        self.params = params

    def reset(self) -> None:
        """Restart on the next ``update`` (PX4 ``reset_state``)."""
        self._initialised = False

    @property
    def mode(self) -> TecsMode:
        return self._mode

    # -- the step ------------------------------------------------------------------------------------

    def update(
        self,
        dt: float,
        *,
        altitude: float,
        vz: float,
        vz_valid: bool,
        az: float,
        airspeed: float,
        speed_derivative: float,
        eas_to_tas: float,
        pitch: float,
        roll: float,
        altitude_sp: float,
        airspeed_sp: float,
        pitch_min: float,
        pitch_max: float,
        throttle_min: float,
        throttle_max: float,
        throttle_trim: float,
        height_rate_sp: float = math.nan,
        climbout: bool = False,
        climbout_pitch_min: float = 0.0,
        in_air: bool = True,
        detect_underspeed: bool = True,
    ) -> TecsOutput:
        """One step of ``dt`` seconds.

        State: ``altitude`` [m, up] and NED ``vz`` [m/s] (``vz_valid`` False: height and rate from the
        baro-inertial filter on ``altitude`` and the NED vertical acceleration ``az``); ``airspeed``
        (EAS [m/s], NaN: none); ``speed_derivative`` [m/s²], the airspeed's rate of change, which PX4
        takes as the body-x kinematic acceleration; ``eas_to_tas``; ``pitch``, ``roll`` [rad].
        Setpoints: ``altitude_sp`` [m, up] (NaN: fly ``height_rate_sp``, NaN = 0, from the present
        altitude), ``airspeed_sp`` (EAS), ``height_rate_sp`` [m/s] (fed forward with an altitude).
        Limits: ``pitch_min/max`` [rad], ``throttle_min/max/trim``; ``climbout`` with its
        ``climbout_pitch_min`` [rad]. Not ``in_air``: nothing is controlled; the outputs are the
        present pitch and ``throttle_min``.
        """
        p = self.params
        if not (math.isfinite(eas_to_tas) and eas_to_tas > 0.0):
            eas_to_tas = 1.0
        if not math.isfinite(throttle_trim):
            throttle_trim = throttle_min
        if not in_air:
            self._initialised = False
            self._throttle_setpoint = throttle_min
            self._pitch_setpoint = constrain(pitch, pitch_min, pitch_max) if math.isfinite(pitch) else 0.0
            self._mode = TecsMode.NORMAL
            return TecsOutput(self._pitch_setpoint, self._throttle_setpoint, self._mode)
        if not (math.isfinite(dt) and dt <= DT_MAX):
            self._initialised = False
            dt = DT_DEFAULT
        if not self._initialised:
            self._initialise(altitude, vz, vz_valid, airspeed, eas_to_tas, pitch, pitch_min, pitch_max, throttle_trim)
        dt = max(dt, DT_MIN)
        airspeed_enabled = math.isfinite(airspeed)
        self._update_vertical_state(dt, altitude, vz, vz_valid, az)
        self._update_airspeed_rate(dt, airspeed_enabled, speed_derivative)
        if climbout:
            pitch_min = climbout_pitch_min
            throttle_min = throttle_max - CLIMBOUT_THROTTLE_MARGIN
        self._throttle_trim = throttle_trim

        eas = airspeed if airspeed_enabled else p.fw_airspd_trim
        self._update_speed_states(dt, eas * eas_to_tas, airspeed_enabled)
        ste_rate_max = max(p.fw_t_clmb_max, FLT_EPSILON) * G
        ste_rate_min = -max(p.fw_t_sink_min, FLT_EPSILON) * G
        self._detect_underspeed(detect_underspeed and not climbout, p.fw_airspd_min * eas_to_tas)
        self._update_weights(airspeed_enabled, climbout)
        self._detect_uncommanded_descent(throttle_max, climbout)
        self._update_speed_setpoint(airspeed_sp, eas_to_tas, ste_rate_min, ste_rate_max)
        self._update_height_rate_setpoint(dt, altitude_sp, height_rate_sp)
        self._update_energies()
        load_factor = 1.0 / constrain(math.cos(roll), LOAD_FACTOR_COS_MIN, 1.0) if math.isfinite(roll) else 1.0
        self._update_throttle(
            dt, airspeed_enabled, load_factor, ste_rate_min, ste_rate_max, throttle_min, throttle_max, climbout
        )
        self._update_pitch(dt, climbout, pitch_min, pitch_max)
        if self._underspeed_ratio > FLT_EPSILON:
            self._mode = TecsMode.UNDERSPEED
        elif self._uncommanded_descent:
            self._mode = TecsMode.BAD_DESCENT
        elif climbout:
            self._mode = TecsMode.CLIMBOUT
        else:
            self._mode = TecsMode.NORMAL
        return TecsOutput(self._pitch_setpoint, self._throttle_setpoint, self._mode)

    # -- steps of the update -------------------------------------------------------------------------

    def _initialise(
        self,
        altitude: float,
        vz: float,
        vz_valid: bool,
        airspeed: float,
        eas_to_tas: float,
        pitch: float,
        pitch_min: float,
        pitch_max: float,
        throttle_trim: float,
    ) -> None:
        p = self.params
        altitude = altitude if math.isfinite(altitude) else 0.0
        eas = airspeed if math.isfinite(airspeed) else p.fw_airspd_trim
        self._vert_pos = altitude
        self._vert_vel = -vz if vz_valid and math.isfinite(vz) else 0.0
        self._vert_accel = 0.0
        self._tas_state = max(eas * eas_to_tas, TAS_STATE_MIN)
        self._tas_rate_state = 0.0
        self._tas_rate_filtered = 0.0
        self._tas_rate_filter.reset(0.0)
        self._ste_rate_error_filter.reset(0.0)
        self._throttle_integ = 0.0
        self._pitch_integ = 0.0
        self._throttle_setpoint = throttle_trim
        self._pitch_setpoint = constrain(pitch, pitch_min, pitch_max) if math.isfinite(pitch) else 0.0
        self._pitch_setpoint_unc = self._pitch_setpoint
        self._tas_setpoint_adj = self._tas_state
        self._hgt_setpoint = altitude
        self._hgt_rate_setpoint = 0.0
        self._alt_trajectory.reset(0.0, 0.0, altitude)
        self._underspeed_ratio = 0.0
        self._uncommanded_descent = False
        self._ste_rate_error = 0.0
        self._initialised = True

    def _update_vertical_state(self, dt: float, altitude: float, vz: float, vz_valid: bool, az: float) -> None:
        if vz_valid and math.isfinite(vz) and math.isfinite(altitude):
            self._vert_vel = -vz
            self._vert_pos = altitude
            return
        if not (math.isfinite(altitude) and math.isfinite(az)):
            return
        # Third-order complementary filter, all three poles at omega (backward Euler).
        omega = self.params.fw_t_hgt_omega
        omega2 = omega * omega
        hgt_err = altitude - self._vert_pos
        self._vert_accel += hgt_err * omega2 * omega * dt
        self._vert_vel += (self._vert_accel - az + hgt_err * omega2 * 3.0) * dt
        self._vert_pos += (self._vert_vel + hgt_err * omega * 3.0) * dt

    def _update_airspeed_rate(self, dt: float, airspeed_enabled: bool, speed_derivative: float) -> None:
        if airspeed_enabled and math.isfinite(speed_derivative):
            self._tas_rate_raw = speed_derivative
            self._tas_rate_filter.set_time_constant(dt, self.params.fw_t_tas_r_tc)
            self._tas_rate_filtered = self._tas_rate_filter.update(speed_derivative)
        else:
            self._tas_rate_raw = 0.0
            self._tas_rate_filtered = 0.0

    def _update_speed_states(self, dt: float, tas_measured: float, airspeed_enabled: bool) -> None:
        """Second-order complementary filter of the true airspeed with its measured rate (PX4
        ``_update_speed_states``)."""
        omega = self.params.fw_t_spd_omega
        self._tas_innov = tas_measured - self._tas_state
        tas_rate_state_input = self._tas_innov * omega * omega
        if self._tas_state < TAS_STATE_MIN + 0.1:
            tas_rate_state_input = max(tas_rate_state_input, 0.0)
        self._tas_rate_state += tas_rate_state_input * dt
        tas_state_input = self._tas_rate_state + self._tas_rate_raw + self._tas_innov * omega * math.sqrt(2.0)
        self._tas_state = max(self._tas_state + tas_state_input * dt, TAS_STATE_MIN)

    def _detect_underspeed(self, enabled: bool, tas_min: float) -> None:
        """How far into underspeed the airspeed is, 0…1 (PX4 v1.14 ``src/lib/tecs/TECS.cpp``,
        ``TECSControl::_detectUnderspeed``)."""
        if not enabled:
            self._underspeed_ratio = 0.0
            return
        # The bounds are fractions of the trim airspeed (EAS), as PX4's.
        error_bound = TAS_ERROR_PERCENTAGE * self.params.fw_airspd_trim
        fully_undersped = max(tas_min - 2.0 * error_bound, 0.0)
        starting_to_underspeed = max(tas_min - error_bound, fully_undersped)
        self._underspeed_ratio = 1.0 - constrain(
            (self._tas_state - fully_undersped) / max(starting_to_underspeed - fully_undersped, FLT_EPSILON), 0.0, 1.0
        )

    def _update_weights(self, airspeed_enabled: bool, climbout: bool) -> None:
        ske_weighting = constrain(self.params.fw_t_spdweight, 0.0, 2.0)
        ratio = self._underspeed_ratio
        if climbout and airspeed_enabled:
            ske_weighting = 2.0
        elif ratio > FLT_EPSILON and airspeed_enabled:
            ske_weighting = 2.0 * ratio + (1.0 - ratio) * ske_weighting
        elif not airspeed_enabled:
            ske_weighting = 0.0
        # No weight above one: it would shorten the loop's time constant and can destabilise it.
        self._spe_weighting = constrain(2.0 - ske_weighting, 0.0, 1.0)
        self._ske_weighting = constrain(ske_weighting, 0.0, 1.0)

    def _detect_uncommanded_descent(self, throttle_max: float, climbout: bool) -> None:
        """The airspeed demand is more than the aircraft can hold level: it sinks at high throttle."""
        if climbout:
            self._uncommanded_descent = False
            return
        ste_rate = self._spe_rate + self._ske_rate
        if (
            not self._uncommanded_descent
            and self._underspeed_ratio <= FLT_EPSILON
            and self._ste_error > DESCENT_ENERGY_ERROR
            and ste_rate < 0.0
            and self._throttle_setpoint >= throttle_max * DESCENT_THROTTLE_RATIO
        ):
            self._uncommanded_descent = True
        elif self._uncommanded_descent and (self._underspeed_ratio > FLT_EPSILON or self._ste_error < 0.0):
            self._uncommanded_descent = False

    def _update_speed_setpoint(
        self, airspeed_sp: float, eas_to_tas: float, ste_rate_min: float, ste_rate_max: float
    ) -> None:
        p = self.params
        tas_min = p.fw_airspd_min * eas_to_tas
        tas_max = p.fw_airspd_max * eas_to_tas
        self._tas_min = tas_min
        eas_sp = airspeed_sp if math.isfinite(airspeed_sp) else p.fw_airspd_trim
        self._eas_setpoint = eas_sp
        tas_sp = eas_sp * eas_to_tas
        if self._uncommanded_descent:
            tas_sp = tas_min
        tas_sp = self._underspeed_ratio * tas_min + (1.0 - self._underspeed_ratio) * tas_sp
        self._tas_setpoint_adj = constrain(tas_sp, tas_min, tas_max)
        # Half the rate the throttle range allows, leaving the rest to correct errors.
        rate_max = 0.5 * ste_rate_max / self._tas_state
        rate_min = 0.5 * ste_rate_min / self._tas_state
        rate = (self._tas_setpoint_adj - self._tas_state) / max(p.fw_t_tas_tc, 0.1)
        self._tas_rate_setpoint = constrain(rate, rate_min, rate_max)

    def _update_height_rate_setpoint(self, dt: float, altitude_sp: float, height_rate_sp: float) -> None:
        p = self.params
        rate_ff = height_rate_sp if math.isfinite(height_rate_sp) else 0.0
        trajectory = self._alt_trajectory
        trajectory.max_accel = p.fw_t_vert_acc
        trajectory.max_vel = max(p.fw_t_clmb_max, p.fw_t_sink_max)
        self._hgt_setpoint_in = altitude_sp
        if math.isfinite(altitude_sp):
            climb_rate = min(p.fw_t_clmb_r_sp, p.fw_t_clmb_max)
            sink_rate = min(p.fw_t_sink_r_sp, p.fw_t_sink_max)
            to_target = altitude_sp - trajectory.pos
            rate_target = math.copysign(
                max_speed_from_distance(JERK_MAX, p.fw_t_vert_acc, abs(to_target), 0.0), to_target
            )
            trajectory.update_durations(constrain(rate_target, -sink_rate, climb_rate))
            trajectory.update_traj(dt)
            self._hgt_setpoint = trajectory.pos
            rate = (
                (trajectory.pos - self._vert_pos) / max(p.fw_t_alt_tc, 0.1) + p.fw_t_hrate_ff * trajectory.vel + rate_ff
            )
        else:
            trajectory.reset(0.0, rate_ff, self._vert_pos)
            self._hgt_setpoint = self._vert_pos
            rate = rate_ff
        self._hgt_rate_setpoint = constrain(rate, -p.fw_t_sink_max, p.fw_t_clmb_max)

    def _update_energies(self) -> None:
        spe_setpoint = self._hgt_setpoint * G
        ske_setpoint = 0.5 * self._tas_setpoint_adj * self._tas_setpoint_adj
        spe_estimate = self._vert_pos * G
        ske_estimate = 0.5 * self._tas_state * self._tas_state
        self._ste_error = spe_setpoint - spe_estimate + ske_setpoint - ske_estimate
        self._spe_rate_setpoint = self._hgt_rate_setpoint * G
        self._ske_rate_setpoint = self._tas_state * self._tas_rate_setpoint
        self._spe_rate = self._vert_vel * G
        self._ske_rate = self._tas_state * self._tas_rate_filtered

    def _update_throttle(
        self,
        dt: float,
        airspeed_enabled: bool,
        load_factor: float,
        ste_rate_min: float,
        ste_rate_max: float,
        throttle_min: float,
        throttle_max: float,
        climbout: bool,
    ) -> None:
        p = self.params
        trim = constrain(self._throttle_trim, throttle_min, throttle_max)
        ste_rate_setpoint = self._spe_rate_setpoint + self._ske_rate_setpoint
        self._ste_rate_error_filter.set_time_constant(dt, p.fw_t_ste_r_tc)
        self._ste_rate_error = self._ste_rate_error_filter.update(
            ste_rate_setpoint - self._spe_rate - self._ske_rate
        )
        ratio = self._underspeed_ratio
        # Induced drag grows with the load factor n = 1/cos(roll): ask for more energy in turns.
        ste_rate_setpoint += p.fw_t_rll2thr * (load_factor - 1.0)
        ste_rate_setpoint = constrain(ste_rate_setpoint, ste_rate_min, ste_rate_max)
        if ste_rate_setpoint >= 0.0:
            predicted = trim + ste_rate_setpoint / ste_rate_max * (throttle_max - trim)
        else:
            predicted = trim + ste_rate_setpoint / ste_rate_min * (throttle_min - trim)
        ste_rate_to_throttle = 1.0 / (ste_rate_max - ste_rate_min)
        throttle = self._ste_rate_error * p.fw_t_thr_damp * ste_rate_to_throttle + predicted
        throttle = constrain(throttle, throttle_min, throttle_max)
        if airspeed_enabled:
            if p.fw_t_i_gain_thr > 0.0:
                integ_max = throttle_max - throttle
                integ_min = throttle_min - throttle
                # Underspeed holds the integrator: the throttle it needs comes from the blend towards the maximum.
                integ_input = self._ste_rate_error * p.fw_t_i_gain_thr * dt * ste_rate_to_throttle * (1.0 - ratio)
                # Only let the integrator move the way that unsaturates the throttle.
                if self._throttle_integ > integ_max:
                    integ_input = min(0.0, integ_input)
                elif self._throttle_integ < integ_min:
                    integ_input = max(0.0, integ_input)
                self._throttle_integ += integ_input
                if climbout:
                    # No throttle dip when climb-out hands over to closed-loop control.
                    self._throttle_integ = integ_max
            else:
                self._throttle_integ = 0.0
            throttle += self._throttle_integ
        else:
            throttle = predicted
        throttle = ratio * throttle_max + (1.0 - ratio) * throttle
        self._throttle_setpoint = constrain(throttle, throttle_min, throttle_max)

    def _seb_rates(self) -> tuple[float, float]:
        """The specific energy balance rate: setpoint and estimate."""
        w_p, w_k = self._spe_weighting, self._ske_weighting
        return (
            self._spe_rate_setpoint * w_p - self._ske_rate_setpoint * w_k,
            self._spe_rate * w_p - self._ske_rate * w_k,
        )

    def _update_pitch(self, dt: float, climbout: bool, pitch_min: float, pitch_max: float) -> None:
        p = self.params
        seb_rate_setpoint, seb_rate = self._seb_rates()
        self._seb_rate_error = seb_rate_setpoint - seb_rate
        # The climb angle follows pitch with a small lag and a constant angle of attack: θ ≈ SEḂ / (g·V).
        climb_angle_to_seb_rate = self._tas_state * G
        if p.fw_t_i_gain_pit > 0.0:
            integ_input = self._seb_rate_error * p.fw_t_i_gain_pit
            if self._pitch_setpoint_unc > pitch_max:
                integ_input = min(integ_input, 0.0)
            elif self._pitch_setpoint_unc < pitch_min:
                integ_input = max(integ_input, 0.0)
            self._pitch_integ += integ_input * dt
        else:
            self._pitch_integ = 0.0
        correction = self._seb_rate_error * p.fw_t_ptch_damp + self._pitch_integ + p.fw_t_seb_r_ff * seb_rate_setpoint
        if climbout:
            # Zero speed error gives the climb-out pitch, with no integrator to catch up first.
            correction += pitch_min * climb_angle_to_seb_rate
        self._pitch_setpoint_unc = correction / climb_angle_to_seb_rate
        pitch = constrain(self._pitch_setpoint_unc, pitch_min, pitch_max)
        # The vertical acceleration limit, as a pitch rate limit.
        increment = dt * p.fw_t_vert_acc / self._tas_state
        self._pitch_setpoint = constrain(pitch, self._pitch_setpoint - increment, self._pitch_setpoint + increment)

    # -- status ----------------------------------------------------------------------------------------

    def status(self) -> TecsStatus:
        """The ``tecs_status`` message of the last update (the caller stamps it)."""
        seb_rate_setpoint, seb_rate = self._seb_rates()
        return TecsStatus(
            altitude_sp=self._hgt_setpoint_in,
            altitude_reference=self._hgt_setpoint,
            height_rate_reference=self._alt_trajectory.vel,
            height_rate_setpoint=self._hgt_rate_setpoint,
            height_rate=self._vert_vel,
            equivalent_airspeed_sp=self._eas_setpoint,
            true_airspeed_sp=self._tas_setpoint_adj,
            true_airspeed_filtered=self._tas_state,
            true_airspeed_derivative_sp=self._tas_rate_setpoint,
            true_airspeed_derivative=self._tas_rate_filtered,
            true_airspeed_derivative_raw=self._tas_rate_raw,
            total_energy_rate_sp=self._spe_rate_setpoint + self._ske_rate_setpoint,
            total_energy_rate=self._spe_rate + self._ske_rate,
            total_energy_balance_rate_sp=seb_rate_setpoint,
            total_energy_balance_rate=seb_rate,
            throttle_integ=self._throttle_integ,
            pitch_integ=self._pitch_integ,
            throttle_sp=self._throttle_setpoint,
            pitch_sp_rad=self._pitch_setpoint,
            throttle_trim=self._throttle_trim,
            underspeed_ratio=self._underspeed_ratio,
        )
