"""fw_att_control: the fixed-wing attitude and rate loops, run on every attitude estimate (PX4 v1.13's
``FixedwingAttitudeControl::Run``, which its vehicle_attitude callback runs; dt within 2–40 ms).

It obeys ``vehicle_control_mode`` as PX4 does:

- manual enabled, no climb-rate loop: with attitude control, Stabilized (the sticks make the attitude setpoint,
  published, the heading free, the yaw stick added to the rudder); with rate control only, Acro (the sticks make
  the rate setpoint); with neither, Manual (the sticks go straight to the surfaces);
- otherwise, with attitude control, the ``vehicle_attitude_setpoint`` of fw_pos_control (q_d, throttle =
  thrust_body[0], wheel steering, integrator reset); with rate control only, ``vehicle_rates_setpoint`` from
  outside;
- no loop enabled: nothing is published.

Out: ``vehicle_rates_setpoint``, ``vehicle_torque_setpoint`` (x aileron, y elevator, z rudder, each in [−1, 1])
and ``vehicle_thrust_setpoint`` (x = throttle in [0, 1]). Disarmed: zero torque and thrust, integrators reset.
"""

from __future__ import annotations

import math

from stack.fw import att_control
from stack.fw.att_control import AttitudeTarget, ControlOutput, FixedwingAttitudeController, StickMapping
from stack.mathlib import quaternion as quat
from stack.mathlib.scalar import constrain
from stack.mathlib.vector import Vec3
from stack.msg.estimation import VehicleAttitude
from stack.msg.fixedwing import AIRSPEED_TIMEOUT_US
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import (
    ManualControlSetpoint,
    RateCtrlStatus,
    VehicleAttitudeSetpoint,
    VehicleRatesSetpoint,
    VehicleThrustSetpoint,
    VehicleTorqueSetpoint,
)
from stack.msg.system import VehicleControlMode
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

_NO_MODE = VehicleControlMode()
_ZERO = (0.0, 0.0, 0.0)


def _clamp_torque(torque: tuple[float, float, float]) -> tuple[float, float, float]:
    return (constrain(torque[0], -1.0, 1.0), constrain(torque[1], -1.0, 1.0), constrain(torque[2], -1.0, 1.0))


def _throttle(value: float) -> float:
    return constrain(value, 0.0, 1.0) if math.isfinite(value) else 0.0


class FixedwingAttitudeControl(Module):
    NAME = "fw_att_control"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Fixed-wing attitude controller (PX4 fw_att_control): attitude → body rates → surfaces, throttle"
    TRIGGER = Trigger(ORB_ID.vehicle_attitude)
    DT_RANGE = (0.002, 0.04)
    PARAMS = att_control.PARAMS
    PUBLISHES = (
        ORB_ID.vehicle_attitude_setpoint,
        ORB_ID.vehicle_rates_setpoint,
        ORB_ID.vehicle_torque_setpoint,
        ORB_ID.vehicle_thrust_setpoint,
        ORB_ID.rate_ctrl_status,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_angular_velocity,
            ORB_ID.vehicle_attitude_setpoint,
            ORB_ID.vehicle_rates_setpoint,
            ORB_ID.vehicle_control_mode,
            ORB_ID.manual_control_setpoint,
            ORB_ID.airspeed_validated,
            ORB_ID.vehicle_land_detected,
            ORB_ID.vehicle_local_position,
            ORB_ID.actuator_armed,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        values = self.params.values()
        self.control = FixedwingAttitudeController(values)
        self.sticks = StickMapping(values)
        self._nonfinite = 0

    def on_params_changed(self, changed: set[str]) -> None:
        values = self.params.values()
        self.control.set_params(values)
        self.sticks.set_params(values)

    def run(self, att: VehicleAttitude, dt: float) -> None:
        t = att.timestamp_sample
        armed = self.latest(ORB_ID.actuator_armed)
        if armed is None or not armed.armed or armed.lockdown or armed.kill:
            self.control.reset_integrals()
            self._publish(t, _ZERO, 0.0)
            return
        mode = self.latest(ORB_ID.vehicle_control_mode) or _NO_MODE
        if not (mode.flag_control_rates_enabled or mode.flag_control_attitude_enabled
                or mode.flag_control_manual_enabled):
            return
        sticks = self._sticks() if mode.flag_control_manual_enabled else None
        stick_modes = sticks is not None and not mode.flag_control_climb_rate_enabled
        if stick_modes and not mode.flag_control_attitude_enabled and not mode.flag_control_rates_enabled:
            self._publish(t, self.sticks.torque(sticks.roll, sticks.pitch, sticks.yaw),
                          StickMapping.throttle(sticks.throttle))
            return
        rates_msg = self.latest(ORB_ID.vehicle_angular_velocity)
        if not mode.flag_control_rates_enabled or rates_msg is None:
            return
        if not quat.is_finite(att.q):
            self.reject("vehicle_attitude with a non-finite q")
            return
        land = self.latest(ORB_ID.vehicle_land_detected)
        landed = land is None or land.landed  # PX4 starts landed until the land detector says otherwise
        pilot = sticks if stick_modes else None
        if mode.flag_control_attitude_enabled:
            step = self._attitude(att, rates_msg.xyz, pilot, mode, dt, landed)
        else:
            step = self._rates(rates_msg.xyz, pilot, dt, landed)
        self._count_nonfinite()
        if step is None:
            return
        out, throttle = step
        self.publish(
            ORB_ID.vehicle_rates_setpoint,
            VehicleRatesSetpoint(roll=out.rates_sp[0], pitch=out.rates_sp[1], yaw=out.rates_sp[2],
                                 thrust_body=(throttle, 0.0, 0.0)),
        )
        self._publish(t, out.torque, throttle)
        integ = self.control.integrals
        self.publish(
            ORB_ID.rate_ctrl_status,
            RateCtrlStatus(rollspeed_integ=integ[0], pitchspeed_integ=integ[1], yawspeed_integ=integ[2]),
        )

    def _attitude(self, att: VehicleAttitude, rates: Vec3, sticks: ManualControlSetpoint | None,
                  mode: VehicleControlMode, dt: float, landed: bool) -> tuple[ControlOutput, float] | None:
        """Stabilized from the sticks (the setpoint published, the yaw stick added to the rudder), or the setpoint
        on the bus."""
        if sticks is not None:
            target = self.sticks.attitude(sticks.roll, sticks.pitch, quat.yaw(att.q))
            throttle = StickMapping.throttle(sticks.throttle)
            q_d = quat.from_euler(target.roll, target.pitch, target.yaw)
            self.publish(ORB_ID.vehicle_attitude_setpoint,
                         VehicleAttitudeSetpoint(q_d=q_d, thrust_body=(throttle, 0.0, 0.0)))
        else:
            setpoint = self.latest(ORB_ID.vehicle_attitude_setpoint)
            if setpoint is None:
                return None
            if not quat.is_finite(setpoint.q_d):
                self.reject("vehicle_attitude_setpoint with a non-finite q_d")
                return None
            if setpoint.reset_integral:
                self.control.reset_integrals()
            roll, pitch, yaw = quat.to_euler(setpoint.q_d)
            # Wheel steering in the auto modes only (PX4 clears fw_control_yaw outside them).
            wheel = setpoint.fw_control_yaw_wheel and mode.flag_control_auto_enabled
            target = AttitudeTarget(roll, pitch, yaw, wheel)
            throttle = _throttle(setpoint.thrust_body[0])
        groundspeed = self._groundspeed() if target.wheel else math.nan
        out = self.control.attitude(att.q, rates, target, self._airspeed(), dt, landed=landed, groundspeed=groundspeed)
        if out is None:
            return None
        if sticks is not None:
            out = ControlOutput(out.rates_sp, (out.torque[0], out.torque[1], out.torque[2] + sticks.yaw))
        return out, throttle

    def _rates(self, rates: Vec3, sticks: ManualControlSetpoint | None, dt: float,
               landed: bool) -> tuple[ControlOutput, float] | None:
        """Acro from the sticks, or the rate setpoint on the bus."""
        if sticks is not None:
            rates_sp = self.sticks.rates(sticks.roll, sticks.pitch, sticks.yaw)
            throttle = StickMapping.throttle(sticks.throttle)
        else:
            external = self.latest(ORB_ID.vehicle_rates_setpoint)
            if external is None:
                return None
            rates_sp = (external.roll, external.pitch, external.yaw)
            throttle = _throttle(external.thrust_body[0])
        out = self.control.rates(rates, rates_sp, self._airspeed(), dt, landed=landed)
        return None if out is None else (out, throttle)

    def _publish(self, t: int, torque: tuple[float, float, float], throttle: float) -> None:
        thrust = VehicleThrustSetpoint(timestamp_sample=t, xyz=(throttle, 0.0, 0.0))
        self.publish(ORB_ID.vehicle_thrust_setpoint, thrust)
        self.publish(
            ORB_ID.vehicle_torque_setpoint, VehicleTorqueSetpoint(timestamp_sample=t, xyz=_clamp_torque(torque))
        )

    def _sticks(self) -> ManualControlSetpoint | None:
        sticks = self.latest(ORB_ID.manual_control_setpoint)
        if sticks is None or not sticks.valid:
            return None
        if not all(math.isfinite(v) for v in (sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle)):
            self.reject("manual_control_setpoint with a non-finite stick")
            return None
        return sticks

    def _airspeed(self) -> float:
        """The validated calibrated airspeed [m/s], NaN when there is none or it is over a second old."""
        msg = self.latest(ORB_ID.airspeed_validated)
        if msg is None or self.now_us() - msg.timestamp > AIRSPEED_TIMEOUT_US:
            return math.nan
        return msg.calibrated_airspeed_m_s

    def _groundspeed(self) -> float:
        pos = self.latest(ORB_ID.vehicle_local_position)
        if pos is None or not pos.v_xy_valid:
            return math.nan
        return math.hypot(pos.vx, pos.vy)

    def _count_nonfinite(self) -> None:
        if self.control.nonfinite_inputs != self._nonfinite:
            self._nonfinite = self.control.nonfinite_inputs
            self.reject("a non-finite attitude, rate or setpoint")
