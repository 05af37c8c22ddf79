"""Stabilized mode's attitude setpoint as an attitude loop makes it from the sticks each cycle: the glue around
:class:`stack.attctl.stabilized.StabilizedAttitudeSetpoint` of PX4's ``MulticopterAttitudeControl::Run``.

As in PX4, the manual thrust limits slew on every cycle whatever the mode (after the setpoint): the minimum to
MPC_MANTHR_MIN in the air and to 0 on the ground, the maximum to 1 from COM_SPOOLUP_TIME after arming. So a switch
to Stabilized in flight has its full thrust range at once.
"""

from __future__ import annotations

from collections.abc import Mapping

from stack.attctl.stabilized import StabilizedAttitudeSetpoint
from stack.mathlib.quaternion import Quat
from stack.msg.setpoints import ManualControlSetpoint, VehicleAttitudeSetpoint
from stack.msg.system import VehicleControlMode


def stabilized_mode(mode: VehicleControlMode) -> bool:
    """Attitude control from the sticks: manual, with no altitude, velocity or position loop (nor RotorS')."""
    return (
        mode.flag_control_manual_enabled
        and mode.flag_control_attitude_enabled
        and not mode.flag_control_rpyt_enabled
        and not mode.flag_control_altitude_enabled
        and not mode.flag_control_velocity_enabled
        and not mode.flag_control_position_enabled
    )


class StickAttitudeSetpoint:
    """The sticks' attitude setpoint in Stabilized, restarted (filters, heading) on entering the mode."""

    __slots__ = ("_armed", "_armed_at_us", "_was_stabilized", "sticks")

    def __init__(self, params: Mapping[str, object] | None = None) -> None:
        self.sticks = StabilizedAttitudeSetpoint(params)
        self._was_stabilized = False
        self._armed = False
        self._armed_at_us = 0

    def set_params(self, params: Mapping[str, object]) -> None:
        self.sticks.set_params(params)

    def update(
        self, q: Quat, mode: VehicleControlMode, sticks: ManualControlSetpoint | None, landed: bool, dt: float,
        now_us: int,
    ) -> VehicleAttitudeSetpoint | None:
        """This cycle's setpoint, or None outside Stabilized or without sticks; call it on every cycle."""
        stabilized = stabilized_mode(mode)
        entered = stabilized and not self._was_stabilized
        self._was_stabilized = stabilized
        if mode.flag_armed and not self._armed:
            self._armed_at_us = now_us
        self._armed = mode.flag_armed
        setpoint = None
        if stabilized and sticks is not None:
            if entered:
                self.sticks.reset()
            sp = self.sticks.generate(
                q, sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle, dt, reset_yaw=not mode.flag_armed
            )
            setpoint = VehicleAttitudeSetpoint(
                yaw_sp_move_rate=sp.yaw_sp_move_rate, q_d=sp.q_d, thrust_body=sp.thrust_body
            )
        self.sticks.update_throttle_limits(dt, landed, mode.flag_armed, now_us, self._armed_at_us)
        return setpoint
