"""One cycle of PX4's ``MulticopterPositionControl::Run``
(``src/modules/mc_pos_control/MulticopterPositionControl.cpp``) around
:class:`~stack.posctl.position_control.PositionControl` and :class:`~stack.posctl.takeoff.Takeoff`, with no I/O:
the mc_pos_control module reads the topics, calls :meth:`PositionLoop.update` and publishes.

While multicopter position control is enabled the loop executes the latest ``trajectory_setpoint`` (zero thrust
until the takeoff ramp starts; the tilt limit and minimum thrust of the takeoff stage; the hover thrust estimate
once valid, with MPC_USE_HTE). A setpoint it cannot execute (none, invalid estimate for a controlled axis, NaN
result) is replaced by PX4's failsafe setpoint: stop, or descend blind when even the velocity estimate is gone.
Outside position control the takeoff stage is skipped, as in PX4, so a switch to position control in the air does
not start a takeoff ramp from zero thrust.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from stack.estimator.acceleration import VelocityDerivative
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.setpoints import HoverThrustEstimate, TakeoffState, TrajectorySetpoint
from stack.msg.system import VehicleLandDetected
from stack.posctl.position_control import PositionControl, PositionControlParams, failsafe_setpoint
from stack.posctl.takeoff import Takeoff, TakeoffParams, wants_takeoff

NAN = math.nan
NAN3 = (NAN, NAN, NAN)
SETPOINT_WAIT_US = 200_000
"""How long after position control is enabled a missing trajectory setpoint is tolerated."""
SETPOINT_TIMEOUT_US = 500_000
"""A trajectory setpoint older than this no longer counts (its producer stopped)."""


class PositionLoopResult(NamedTuple):
    """What a cycle did: whether there are setpoints to publish, and whether a kept velocity integral was resumed
    (True), refused as unusable (False) or not tried (None)."""

    setpoints: bool
    resumed_integral: bool | None = None


class PositionLoop:
    """``update`` once per local position estimate; ``control`` then holds the setpoints to publish and ``takeoff``
    the takeoff stage. ``failsafe_action`` names the failsafe setpoint flown ("" while the setpoint is executed)."""

    def __init__(
        self,
        control: PositionControlParams,
        takeoff: TakeoffParams,
        *,
        use_hover_thrust_estimate: bool,
        land_speed: float,
        velocity_derivative_cutoff: float,
        kept_integral: list[float] | None = None,
    ) -> None:
        self.control = PositionControl(control)
        self.takeoff = Takeoff(takeoff)
        self.velocity_derivative = VelocityDerivative(velocity_derivative_cutoff)
        self._p = control
        self._use_hte = use_hover_thrust_estimate
        self._land_speed = land_speed
        self._enabled_since_us = 0
        self._first_run = True
        self.failsafe_action = ""
        self._kept_integral = kept_integral
        """A velocity integral kept by an instance that crashed, resumed when control starts in the air."""

    def set_params(
        self,
        control: PositionControlParams,
        takeoff: TakeoffParams,
        *,
        use_hover_thrust_estimate: bool,
        land_speed: float,
        velocity_derivative_cutoff: float | None = None,
    ) -> None:
        """New parameters; a new velocity-derivative cutoff (not None) restarts that filter."""
        self.control.set_params(control)
        self.takeoff.set_params(takeoff)
        self._p = control
        self._use_hte = use_hover_thrust_estimate
        self._land_speed = land_speed
        if velocity_derivative_cutoff is not None:
            self.velocity_derivative = VelocityDerivative(velocity_derivative_cutoff)

    def update(
        self,
        now: int,
        dt: float,
        lpos: VehicleLocalPosition,
        *,
        enabled: bool,
        armed: bool,
        land: VehicleLandDetected | None,
        setpoint: TrajectorySetpoint | None,
        hover_thrust_estimate: HoverThrustEstimate | None,
    ) -> PositionLoopResult:
        """One cycle at ``now`` on the estimate ``lpos``: ``enabled`` is vehicle_control_mode's multicopter position
        control, ``land`` the land detector's latest (None: none yet), ``setpoint`` the latest trajectory setpoint."""
        landed = land is None or land.landed
        vel_dot = self.velocity_derivative.update(lpos.timestamp_sample, (lpos.vx, lpos.vy, lpos.vz))
        if not enabled:
            self._enabled_since_us = 0
            self.takeoff.update_state(
                lpos.timestamp_sample, armed=armed, landed=landed, want_takeoff=False, skip_takeoff=True
            )
            return PositionLoopResult(False)
        if land is None:
            # Restarted in flight: the takeoff state waits for the land detector's word, not "landed".
            return PositionLoopResult(False)
        if self._first_run:
            self._first_run = False
            # Started armed in the air (restarted after a crash): flying already, no takeoff from zero thrust.
            self.takeoff.update_state(
                lpos.timestamp_sample, armed=armed, landed=landed, want_takeoff=False, skip_takeoff=not landed
            )
        resumed = None
        if not self._enabled_since_us:
            self._enabled_since_us = now
            self.control.reset_integral()
            if self._kept_integral is not None and not landed:
                resumed = self.control.resume_integral(self._kept_integral)
            self._kept_integral = None

        position = (lpos.x if lpos.xy_valid else NAN, lpos.y if lpos.xy_valid else NAN, lpos.z if lpos.z_valid else NAN)
        velocity = (
            lpos.vx if lpos.v_xy_valid else NAN,
            lpos.vy if lpos.v_xy_valid else NAN,
            lpos.vz if lpos.v_z_valid else NAN,
        )
        accel = vel_dot if vel_dot is not None else (0.0, 0.0, 0.0)
        accel = tuple(a if math.isfinite(v) else NAN for a, v in zip(accel, velocity, strict=True))
        self.control.set_state(position, velocity, accel, lpos.heading)

        setpoint = self._fresh(setpoint, now)
        if setpoint is None and now - self._enabled_since_us < SETPOINT_WAIT_US:
            return PositionLoopResult(False, resumed)
        sp_pos = setpoint.position if setpoint is not None else NAN3
        sp_vel = setpoint.velocity if setpoint is not None else NAN3
        sp_acc = setpoint.acceleration if setpoint is not None else NAN3
        yaw = setpoint.yaw if setpoint is not None else NAN
        yawspeed = setpoint.yawspeed if setpoint is not None else NAN

        p = self._p
        state = self.takeoff.update_state(
            lpos.timestamp_sample,
            armed=armed,
            landed=landed,
            want_takeoff=wants_takeoff(sp_pos[2], sp_vel[2], position[2]),
        )
        flying = state >= TakeoffState.FLIGHT
        if not flying:
            self.control.set_hover_thrust(p.mpc_thr_hover)
        else:
            self._adopt_hover_thrust_estimate(hover_thrust_estimate)
        shaped = self.takeoff.shape_setpoint(sp_pos, sp_vel, sp_acc)
        sp_pos, sp_vel, sp_acc = shaped.position, shaped.velocity, shaped.acceleration
        if flying and land.ground_contact:
            sp_pos, sp_vel, sp_acc = NAN3, NAN3, (0.0, 0.0, 100.0)
            yaw = yawspeed = NAN
            self.control.reset_integral()
        elif shaped.reset_integral:
            yaw = yawspeed = NAN
            self.control.reset_integral()
        speed_up = self.takeoff.update_ramp(dt, p.mpc_z_vel_max_up)
        self.control.set_limits(
            vel_horizontal=min(p.mpc_xy_vel_max, lpos.vxy_max),
            vel_up=min(speed_up, p.mpc_z_vel_max_up),
            vel_down=p.mpc_z_vel_max_dn,
            thrust_min=self.takeoff.minimum_thrust(p.mpc_thr_min),
            tilt_max=self.takeoff.update_tilt_limit(dt),
        )
        self.control.set_setpoint(sp_pos, sp_vel, sp_acc, yaw, yawspeed)
        if not self.control.update(dt):
            self._fly_failsafe(velocity, dt)
        else:
            self.failsafe_action = ""
        return PositionLoopResult(True, resumed)

    def _fresh(self, sp: TrajectorySetpoint | None, now: int) -> TrajectorySetpoint | None:
        if sp is None or sp.timestamp < self._enabled_since_us or now - sp.timestamp > SETPOINT_TIMEOUT_US:
            return None
        return sp

    def _adopt_hover_thrust_estimate(self, hte: HoverThrustEstimate | None) -> None:
        if not self._use_hte:
            return
        if (
            hte is not None
            and hte.valid
            and math.isfinite(hte.hover_thrust)
            and abs(hte.hover_thrust - self.control.hover_thrust) > 1e-6
        ):
            self.control.update_hover_thrust(hte.hover_thrust)

    def _fly_failsafe(self, velocity, dt: float) -> None:
        fs = failsafe_setpoint(velocity, self._land_speed)
        self.failsafe_action = fs.action
        p = self._p
        self.control.set_limits(
            vel_horizontal=p.mpc_xy_vel_max,
            vel_up=p.mpc_z_vel_max_up,
            vel_down=p.mpc_z_vel_max_dn,
        )
        self.control.set_setpoint(fs.position, fs.velocity, fs.acceleration, NAN, NAN)
        self.control.update(dt)
