"""Pilot-controlled flight tasks: Position and Altitude modes from the sticks (PX4 ``FlightTaskManual*``).

Position mode (``FlightTaskManualPosition`` with MPC_POS_MODE 0, direct velocity): the right stick
commands a horizontal velocity in the heading frame up to MPC_VEL_MANUAL, the throttle stick a climb
or descent rate up to MPC_Z_VEL_MAX_UP/DN, the yaw stick a yaw rate up to MPC_MAN_Y_MAX. With a stick
centred (within MPC_HOLD_DZ) and the vehicle slower than MPC_HOLD_MAX_XY / MPC_HOLD_MAX_Z on that axis,
the position there is locked and held. Altitude mode (``FlightTaskManualAltitude``) controls height the
same way but leaves the horizontal axes to the pilot: the stick tilts the thrust up to MPC_MAN_TILT_MAX.
Without valid sticks both modes hold where they are.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from stack.mathlib.scalar import CONSTANTS_ONE_G, deadzone, wrap_pi
from stack.mathlib.vector import Vec3
from stack.msg.setpoints import ManualControlSetpoint
from stack.params.binding import ParamSet
from stack.posctl.flight_task import NAN, TrajectoryCommand, VehicleState


class Sticks:
    """Stick deflections in [−1, 1] after the hold dead zone; all zero when the sticks are invalid."""

    __slots__ = ("forward", "right", "up", "yaw")

    def __init__(self, manual: ManualControlSetpoint | None, dz: float) -> None:
        valid = manual is not None and manual.valid
        self.forward = deadzone(manual.pitch, dz) if valid else 0.0
        self.right = deadzone(manual.roll, dz) if valid else 0.0
        self.up = deadzone(manual.throttle, dz) if valid else 0.0
        self.yaw = deadzone(manual.yaw, dz) if valid else 0.0


def heading_to_ned(forward: float, right: float, yaw: float) -> tuple[float, float]:
    c, s = math.cos(yaw), math.sin(yaw)
    return (forward * c - right * s, forward * s + right * c)


class ManualTaskParams(ParamSet):
    """The sticks' dead zone, the speeds below which position and altitude lock, and the full-stick speeds, tilt
    and yaw rate of Position and Altitude mode (the catalogue's MPC_*)."""

    mpc_hold_dz: float
    mpc_hold_max_xy: float
    mpc_hold_max_z: float
    mpc_vel_manual: float
    mpc_man_tilt_max: float
    mpc_man_y_max: float
    mpc_z_vel_max_up: float
    mpc_z_vel_max_dn: float


class ManualAltitudeTask:
    """Altitude mode: climb rate from the throttle stick with altitude lock; tilt from the right stick."""

    def __init__(self, params: Mapping[str, object]) -> None:
        self.p = ManualTaskParams.from_params(params)
        self._yaw = NAN
        self._lock_z = NAN

    def set_params(self, params: Mapping[str, object]) -> None:
        self.p = ManualTaskParams.from_params(params)

    def activate(self, state: VehicleState) -> None:
        """Lock where the vehicle is if it is (nearly) still; a moving vehicle first brakes, then locks."""
        self._yaw = state.yaw
        vz = state.velocity[2]
        slow = not math.isfinite(vz) or abs(vz) < self.p.mpc_hold_max_z
        self._lock_z = state.position[2] if slow else NAN

    def _vertical(self, sticks: Sticks, state: VehicleState) -> tuple[float, float]:
        """(position z, velocity z) from the throttle stick with the altitude lock."""
        p = self.p
        if sticks.up != 0.0:
            self._lock_z = NAN
            rate = p.mpc_z_vel_max_up if sticks.up > 0.0 else p.mpc_z_vel_max_dn
            return NAN, -sticks.up * rate
        vz = state.velocity[2]
        if math.isnan(self._lock_z) and (not math.isfinite(vz) or abs(vz) < p.mpc_hold_max_z):
            self._lock_z = state.position[2]
        if math.isfinite(self._lock_z):
            return self._lock_z, 0.0
        return NAN, 0.0

    def _heading(self, sticks: Sticks, dt: float) -> tuple[float, float]:
        rate = sticks.yaw * math.radians(self.p.mpc_man_y_max)
        if math.isfinite(self._yaw):
            self._yaw = wrap_pi(self._yaw + rate * dt)
        return self._yaw, rate

    def update(self, state: VehicleState, manual: ManualControlSetpoint | None, dt: float) -> TrajectoryCommand:
        sticks = Sticks(manual, self.p.mpc_hold_dz)
        z, vz = self._vertical(sticks, state)
        yaw, yawspeed = self._heading(sticks, dt)
        tilt = math.radians(self.p.mpc_man_tilt_max)
        ax, ay = heading_to_ned(
            CONSTANTS_ONE_G * math.tan(sticks.forward * tilt), CONSTANTS_ONE_G * math.tan(sticks.right * tilt), yaw
        )
        return TrajectoryCommand(
            position=(NAN, NAN, z), velocity=(NAN, NAN, vz), acceleration=(ax, ay, NAN), yaw=yaw, yawspeed=yawspeed
        )


class ManualPositionTask(ManualAltitudeTask):
    """Position mode: horizontal velocity from the right stick, position lock when it is centred."""

    def __init__(self, params: Mapping[str, object]) -> None:
        super().__init__(params)
        self._lock_xy: tuple[float, float] | None = None

    def activate(self, state: VehicleState) -> None:
        super().activate(state)
        slow = math.hypot(state.velocity[0], state.velocity[1]) < self.p.mpc_hold_max_xy
        self._lock_xy = (state.position[0], state.position[1]) if slow else None

    def update(self, state: VehicleState, manual: ManualControlSetpoint | None, dt: float) -> TrajectoryCommand:
        p = self.p
        sticks = Sticks(manual, p.mpc_hold_dz)
        z, vz = self._vertical(sticks, state)
        yaw, yawspeed = self._heading(sticks, dt)
        x = y = NAN
        if sticks.forward != 0.0 or sticks.right != 0.0:
            self._lock_xy = None
            speed = p.mpc_vel_manual
            vx, vy = heading_to_ned(sticks.forward * speed, sticks.right * speed, yaw)
        else:
            vx = vy = 0.0
            # A lock taken without a position (NaN) is taken again once there is one, as for the altitude.
            unlocked = self._lock_xy is None or math.isnan(self._lock_xy[0])
            if unlocked and math.hypot(state.velocity[0], state.velocity[1]) < p.mpc_hold_max_xy:
                self._lock_xy = (state.position[0], state.position[1])
            if self._lock_xy is not None:
                x, y = self._lock_xy
        position: Vec3 = (x, y, z)
        return TrajectoryCommand(position=position, velocity=(vx, vy, vz), yaw=yaw, yawspeed=yawspeed)
