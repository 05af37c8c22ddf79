"""Smooth takeoff handling of the multicopter position controller (PX4 ``Takeoff``).

Follows ``src/modules/mc_pos_control/Takeoff/Takeoff.cpp`` and the way
``MulticopterPositionControl.cpp`` applies it. States: disarmed → spoolup (motors spinning up for
COM_SPOOLUP_TIME after arming) → ready_for_takeoff → rampup (the upward velocity limit ramps over
MPC_TKO_RAMP_T from −g/MPC_Z_VEL_P_ACC, i.e. from zero thrust, to the takeoff speed) → flight.
Before the ramp the controller gets a 100 m/s² downward acceleration setpoint (zero thrust) and its
integrators are reset; until flight the tilt is limited to MPC_TILTMAX_LND and the minimum thrust
is 0. The tilt limit then slews to MPC_TILTMAX_AIR at 0.2 rad/s.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.mathlib.scalar import CONSTANTS_ONE_G
from stack.mathlib.vector import NAN3, Vec3
from stack.msg.setpoints import TakeoffState
from stack.params.binding import ParamSet

IDLE_ACCELERATION: Vec3 = (0.0, 0.0, 100.0)
"""Acceleration setpoint that drives the collective thrust to zero (far more than gravity, down)."""

TILT_LIMIT_SLEW_RATE = 0.2
"""Slew rate of the tilt limit [rad/s] (MulticopterPositionControl)."""


class TakeoffParams(ParamSet):
    """Tunables of ``Takeoff`` (the catalogue's): COM_SPOOLUP_TIME, the ramp (MPC_TKO_RAMP_T, MPC_TKO_SPEED, its
    start −g/MPC_Z_VEL_P_ACC: zero thrust) and the tilt limits on the ground and in flight."""

    com_spoolup_time: float
    mpc_tko_ramp_t: float
    mpc_tko_speed: float
    mpc_z_vel_p_acc: float
    mpc_tiltmax_lnd: float
    mpc_tiltmax_air: float


class TakeoffSetpoint(NamedTuple):
    """A setpoint triple adjusted for the takeoff state, and whether to reset the integrators."""

    position: Vec3
    velocity: Vec3
    acceleration: Vec3
    reset_integral: bool


class Takeoff:
    """PX4's takeoff state machine and the controller limits it imposes.

    Per position-control cycle: ``update_state(...)``, then ``update_ramp(dt, speed)`` (upward
    velocity limit for ``PositionControl.set_limits(vel_up=...)``), ``update_tilt_limit(dt)``,
    ``minimum_thrust(MPC_THR_MIN)`` and ``shape_setpoint(...)`` for the setpoint to control.
    """

    __slots__ = (
        "_params",
        "_ramp_progress",
        "_ramp_vz_init",
        "_spoolup_since_us",
        "_state",
        "_tilt_limit",
    )

    def __init__(self, params: TakeoffParams | None = None) -> None:
        self._params = params or TakeoffParams()
        self._state = TakeoffState.DISARMED
        self._ramp_progress = 0.0
        self._spoolup_since_us: int | None = None
        self._tilt_limit = math.radians(self._params.mpc_tiltmax_lnd)
        self._ramp_vz_init = 0.0
        self.set_params(self._params)

    def set_params(self, params: TakeoffParams) -> None:
        self._params = params
        self._ramp_vz_init = -CONSTANTS_ONE_G / max(params.mpc_z_vel_p_acc, 0.01)

    @property
    def state(self) -> TakeoffState:
        return self._state

    @property
    def flying(self) -> bool:
        return self._state >= TakeoffState.FLIGHT

    @property
    def tilt_limit(self) -> float:
        """Current (slewed) tilt limit [rad]."""
        return self._tilt_limit

    def update_state(
        self,
        timestamp_us: int,
        *,
        armed: bool,
        landed: bool,
        want_takeoff: bool,
        skip_takeoff: bool = False,
    ) -> TakeoffState:
        """Advance the state machine; several transitions may happen in one call, as in PX4.

        want_takeoff: a setpoint asks to climb (PX4 ``vehicle_constraints.want_takeoff``);
        skip_takeoff: jump straight to flight when armed (e.g. armed in the air; in the air, with the
        flight tilt limit at once).
        """
        # Spool-up timer: true COM_SPOOLUP_TIME after the vehicle was armed.
        if armed:
            if self._spoolup_since_us is None:
                self._spoolup_since_us = timestamp_us
            spooled_up = timestamp_us - self._spoolup_since_us >= self._params.com_spoolup_time * 1e6
        else:
            self._spoolup_since_us = None
            spooled_up = False

        state = self._state
        if state == TakeoffState.DISARMED and armed:
            state = TakeoffState.SPOOLUP
        if state == TakeoffState.SPOOLUP and spooled_up:
            state = TakeoffState.READY_FOR_TAKEOFF
        if state == TakeoffState.READY_FOR_TAKEOFF and want_takeoff:
            state = TakeoffState.RAMPUP
            self._ramp_progress = 0.0
        if state == TakeoffState.RAMPUP and self._ramp_progress >= 1.0:
            state = TakeoffState.FLIGHT
        if state == TakeoffState.FLIGHT and landed:
            state = TakeoffState.READY_FOR_TAKEOFF

        if armed and skip_takeoff:
            if state != TakeoffState.FLIGHT and not landed:
                # Already flying (a restart in the air): no slew up from the ground's tilt limit, which
                # would tip a vehicle leaning into the wind upright and let the wind carry it off.
                self._tilt_limit = math.radians(self._params.mpc_tiltmax_air)
            state = TakeoffState.FLIGHT
        if not armed:
            state = TakeoffState.DISARMED
        self._state = state
        return state

    def update_ramp(self, dt: float, takeoff_speed: float | None = None) -> float:
        """Upward velocity limit [m/s, positive up] for this cycle.

        Before the ramp it is −g/MPC_Z_VEL_P_ACC (a downward velocity setpoint whose P term
        cancels gravity, i.e. zero thrust); during the ramp it moves linearly to ``takeoff_speed``
        (default MPC_TKO_SPEED) over MPC_TKO_RAMP_T; afterwards it is ``takeoff_speed``.
        """
        speed = self._params.mpc_tko_speed if takeoff_speed is None else takeoff_speed
        if self._state < TakeoffState.RAMPUP:
            return self._ramp_vz_init
        if self._state == TakeoffState.RAMPUP:
            ramp_time = self._params.mpc_tko_ramp_t
            if ramp_time > dt:
                self._ramp_progress += dt / ramp_time
            else:
                self._ramp_progress = 1.0
            if self._ramp_progress < 1.0:
                return self._ramp_vz_init + self._ramp_progress * (speed - self._ramp_vz_init)
        return speed

    def update_tilt_limit(self, dt: float) -> float:
        """Tilt limit [rad]: MPC_TILTMAX_LND until flight, then MPC_TILTMAX_AIR, slewed at 0.2 rad/s."""
        tilt_deg = self._params.mpc_tiltmax_air if self.flying else self._params.mpc_tiltmax_lnd
        target = math.radians(tilt_deg)
        step = TILT_LIMIT_SLEW_RATE * dt
        self._tilt_limit = min(max(target, self._tilt_limit - step), self._tilt_limit + step)
        return self._tilt_limit

    def minimum_thrust(self, thrust_min: float) -> float:
        """Minimum collective thrust: 0 until flying (so the ramp can start from zero), else MPC_THR_MIN."""
        return thrust_min if self.flying else 0.0

    def shape_setpoint(self, position: Vec3, velocity: Vec3, acceleration: Vec3) -> TakeoffSetpoint:
        """The setpoint the position controller should execute in the current takeoff state.

        Before the ramp: no position/velocity control, the zero-thrust acceleration and an
        integrator reset. During the ramp: the vertical acceleration feed-forward is dropped so it
        cannot amend the ramp. In flight: unchanged.
        """
        if self._state < TakeoffState.RAMPUP:
            return TakeoffSetpoint(NAN3, NAN3, IDLE_ACCELERATION, True)
        if self._state == TakeoffState.RAMPUP:
            return TakeoffSetpoint(position, velocity, (acceleration[0], acceleration[1], math.nan), False)
        return TakeoffSetpoint(position, velocity, acceleration, False)


TAKEOFF_MIN_ALTITUDE = 0.2
"""A position setpoint this far above the vehicle [m] asks for a takeoff (PX4 ``FlightTask::_checkTakeoff``)."""
TAKEOFF_MIN_CLIMB_RATE = 0.3
"""An upward velocity setpoint faster than this [m/s] asks for a takeoff."""


def wants_takeoff(position_sp_z: float, velocity_sp_z: float, z: float) -> bool:
    """Whether a setpoint asks to leave the ground (NED: up is negative; NaN setpoints ask nothing)."""
    by_position = math.isfinite(position_sp_z) and math.isfinite(z) and position_sp_z < z - TAKEOFF_MIN_ALTITUDE
    by_velocity = math.isfinite(velocity_sp_z) and velocity_sp_z < -TAKEOFF_MIN_CLIMB_RATE
    return by_position or by_velocity
