"""mc_att_control: the attitude loop, run on every attitude estimate.

It obeys ``vehicle_control_mode`` as PX4's mc_att_control did while it had rattitude:

- attitude control enabled: rates from the attitude error (PX4's tilt-prioritised law), the
  setpoint coming from ``vehicle_attitude_setpoint`` or, in Stabilized, from the sticks; optionally
  through ArduPilot's input shaping (MC_INPUT_SHAPING), whose target rates are fed forward;
- the RotorS mode: the sticks mapped as RotorS' joystick interface maps them (roll, pitch, yaw rate, thrust in
  newtons, published on ``roll_pitch_yawrate_thrust_setpoint``) make the attitude setpoint;
- rattitude: above MC_RATT_TH roll/pitch stick deflection the sticks command rates, below attitude;
- manual rates (acro): rates from the sticks;
- otherwise it stays silent and the rate loop follows ``vehicle_rates_setpoint`` from elsewhere.
"""

from __future__ import annotations

from stack.attctl import attitude_control, input_shaping, rate_control, rotors_joy, stabilized
from stack.attctl.attitude_control import AttitudeControl
from stack.attctl.input_shaping import AttitudeSetpointShaping
from stack.attctl.rate_control import AcroStickMapping
from stack.attctl.rotors_joy import JoyMapping
from stack.attctl.stabilized import StabilizedAttitudeSetpoint, rattitude_uses_rate_control, rotors_attitude_setpoint
from stack.mathlib import quaternion as quat
from stack.mixer.effectiveness import collective_thrust_max
from stack.msg.estimation import VehicleAttitude
from stack.msg.setpoints import RollPitchYawrateThrustSetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import VehicleControlMode
from stack.params import ca, catalogue
from stack.params.param import Param
from stack.runtime.module import Module, Trigger

_NO_MODE = VehicleControlMode()


def _unique(*groups: tuple[Param, ...]) -> tuple[Param, ...]:
    seen: dict[str, Param] = {}
    for group in groups:
        for p in group:
            seen.setdefault(p.name, p)
    return tuple(seen.values())


class MulticopterAttitudeControl(Module):
    NAME = "mc_att_control"
    DESCRIPTION = "Attitude controller (PX4 mc_att_control): attitude setpoint → body-rate setpoint"
    TRIGGER = Trigger("vehicle_attitude")
    DT_RANGE = (0.0002, 0.02)
    PARAMS = _unique(
        attitude_control.PARAMS,
        input_shaping.PARAMS,
        stabilized.PARAMS,
        rate_control.ACRO_PARAMS,
        rotors_joy.PARAMS,
        ca.ROTOR_PARAMS,
        catalogue.params("MC_INPUT_SHAPING"),
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            "vehicle_attitude_setpoint",
            "vehicle_control_mode",
            "manual_control_setpoint",
            "vehicle_angular_velocity",
        ):
            self.subscribe(topic)
        self.advertise("vehicle_rates_setpoint")
        self.advertise("vehicle_attitude_setpoint")
        self.advertise("roll_pitch_yawrate_thrust_setpoint")
        values = self.params.values()
        self.control = AttitudeControl(values)
        self.shaping = AttitudeSetpointShaping(values, bool(values["MC_INPUT_SHAPING"]))
        self.sticks = StabilizedAttitudeSetpoint(values)
        self.acro = AcroStickMapping(values)
        self.joy = JoyMapping(values)
        self._thrust_max = collective_thrust_max(values)
        self._reset_counter = 0
        self._was_stabilized = False

    def on_params_changed(self, changed: set[str]) -> None:
        values = self.params.values()
        self.control.set_params(values)
        self.shaping.set_params(values, bool(values["MC_INPUT_SHAPING"]))
        self.sticks.set_params(values)
        self.acro.set_params(values)
        self.joy.set_params(values)
        self._thrust_max = collective_thrust_max(values)

    def run(self, att: VehicleAttitude, dt: float) -> None:
        q = att.q
        if att.quat_reset_counter != self._reset_counter:
            self._reset_counter = att.quat_reset_counter
            self.control.adapt_to_reset(att.delta_q_reset)
            self.shaping.adapt_to_reset(att.delta_q_reset)
        mode = self.latest("vehicle_control_mode") or _NO_MODE
        sticks = self.latest("manual_control_setpoint")
        attitude_enabled = mode.flag_control_attitude_enabled
        if (
            mode.flag_control_rattitude_enabled
            and sticks is not None
            and rattitude_uses_rate_control(sticks.roll, sticks.pitch, float(self.params["MC_RATT_TH"]))
        ):
            attitude_enabled = False  # rattitude: large stick deflections fly rates
        if attitude_enabled:
            self._attitude(q, mode, sticks, dt)
        elif mode.flag_control_manual_enabled and mode.flag_control_rates_enabled and sticks is not None:
            self.shaping.release()
            rates = self.acro.rates(sticks.roll, sticks.pitch, sticks.yaw)
            thrust = AcroStickMapping.thrust_body(sticks.throttle)
            self.publish(
                "vehicle_rates_setpoint",
                VehicleRatesSetpoint(roll=rates[0], pitch=rates[1], yaw=rates[2], thrust_body=thrust),
            )
        else:
            self.shaping.release()

    def _attitude(self, q: tuple[float, float, float, float], mode: VehicleControlMode, sticks, dt: float) -> None:
        stabilized_mode = (
            mode.flag_control_manual_enabled
            and not mode.flag_control_altitude_enabled
            and not mode.flag_control_velocity_enabled
            and not mode.flag_control_position_enabled
            and not mode.flag_control_rpyt_enabled
        )
        if mode.flag_control_rpyt_enabled and sticks is not None:
            setpoint = self._rotors(q, sticks)
        elif stabilized_mode and sticks is not None:
            if not self._was_stabilized:
                self.sticks.reset()
            self.sticks.update_throttle_limits(
                dt, landed=False, armed=mode.flag_armed, now_us=self.now_us(), armed_time_us=0
            )
            sp = self.sticks.generate(
                q, sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle, dt, reset_yaw=not mode.flag_armed
            )
            setpoint = VehicleAttitudeSetpoint(
                yaw_sp_move_rate=sp.yaw_sp_move_rate, q_d=sp.q_d, thrust_body=sp.thrust_body
            )
            self.publish("vehicle_attitude_setpoint", setpoint)
        else:
            setpoint = self.latest("vehicle_attitude_setpoint")
        self._was_stabilized = stabilized_mode
        if setpoint is None or not quat.is_finite(setpoint.q_d):
            return
        rates = self.shaping.rates(self.control, setpoint.q_d, setpoint.yaw_sp_move_rate, q, self._body_rates(), dt)
        self.publish(
            "vehicle_rates_setpoint",
            VehicleRatesSetpoint(roll=rates[0], pitch=rates[1], yaw=rates[2], thrust_body=setpoint.thrust_body),
        )

    def _rotors(self, q: tuple[float, float, float, float], sticks) -> VehicleAttitudeSetpoint:
        command = self.joy.command(sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle)
        self.publish(
            "roll_pitch_yawrate_thrust_setpoint",
            RollPitchYawrateThrustSetpoint(
                timestamp_sample=sticks.timestamp_sample,
                roll=command.roll,
                pitch=command.pitch,
                yaw_rate=command.yaw_rate,
                thrust=command.thrust,
            ),
        )
        sp = rotors_attitude_setpoint(q, command, self._thrust_max)
        setpoint = VehicleAttitudeSetpoint(yaw_sp_move_rate=sp.yaw_sp_move_rate, q_d=sp.q_d, thrust_body=sp.thrust_body)
        self.publish("vehicle_attitude_setpoint", setpoint)
        return setpoint

    def _body_rates(self) -> tuple[float, float, float]:
        """Measured body rates: at large tilt errors the shaper's yaw demand blends toward the yaw rate."""
        rates = self.latest("vehicle_angular_velocity")
        return (0.0, 0.0, 0.0) if rates is None else rates.xyz
