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
from stack.attctl.stabilized import rattitude_uses_rate_control, rotors_attitude_setpoint
from stack.attctl.stick_attitude import StickAttitudeSetpoint
from stack.mathlib import quaternion as quat
from stack.mathlib.scalar import wrap_pi
from stack.mixer.effectiveness import collective_thrust_max
from stack.msg.estimation import VehicleAttitude
from stack.msg.registry import ORB_ID
from stack.msg.setpoints import RollPitchYawrateThrustSetpoint, VehicleAttitudeSetpoint, VehicleRatesSetpoint
from stack.msg.system import VehicleControlMode
from stack.params import ca, catalogue
from stack.params.binding import combine
from stack.runtime.module import Module, Trigger
from stack.runtime.priority import NAV_AND_CONTROLLERS

_NO_MODE = VehicleControlMode()


class MulticopterAttitudeControl(Module):
    NAME = "mc_att_control"
    WORK_QUEUE = NAV_AND_CONTROLLERS
    DESCRIPTION = "Attitude controller (PX4 mc_att_control): attitude setpoint → body-rate setpoint"
    TRIGGER = Trigger(ORB_ID.vehicle_attitude)
    DT_RANGE = (0.0002, 0.02)
    PARAMS = combine(
        attitude_control.PARAMS,
        input_shaping.PARAMS,
        stabilized.PARAMS,
        rate_control.ACRO_PARAMS,
        rotors_joy.PARAMS,
        ca.ROTOR_PARAMS,
        catalogue.params("MC_INPUT_SHAPING"),
    )
    PUBLISHES = (
        ORB_ID.vehicle_rates_setpoint,
        ORB_ID.vehicle_attitude_setpoint,
        ORB_ID.roll_pitch_yawrate_thrust_setpoint,
    )

    def __init__(self, rt) -> None:
        super().__init__(rt)
        for topic in (
            ORB_ID.vehicle_attitude_setpoint,
            ORB_ID.vehicle_control_mode,
            ORB_ID.manual_control_setpoint,
            ORB_ID.vehicle_angular_velocity,
            ORB_ID.vehicle_land_detected,
        ):
            self.subscribe(topic)
        for topic in self.PUBLISHES:
            self.advertise(topic)
        values = self.params.values()
        self.control = AttitudeControl(values)
        self.shaping = AttitudeSetpointShaping(values, bool(values["MC_INPUT_SHAPING"]))
        self.sticks = StickAttitudeSetpoint(values)
        self.acro = AcroStickMapping(values)
        self.joy = JoyMapping(values)
        self._thrust_max = collective_thrust_max(values)
        self._reset_counter = 0
        self._rotors_heading: float | None = None
        """The RotorS mode's heading setpoint [rad], integrated from its yaw rate (None outside the mode)."""

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
            self._rotors_heading = None
        mode = self.latest(ORB_ID.vehicle_control_mode) or _NO_MODE
        sticks = self.latest(ORB_ID.manual_control_setpoint)
        land = self.latest(ORB_ID.vehicle_land_detected)
        stick_setpoint = self.sticks.update(q, mode, sticks, land is not None and land.landed, dt, self.now_us())
        attitude_enabled = mode.flag_control_attitude_enabled
        if (
            mode.flag_control_rattitude_enabled
            and sticks is not None
            and rattitude_uses_rate_control(sticks.roll, sticks.pitch, float(self.params["MC_RATT_TH"]))
        ):
            attitude_enabled = False  # rattitude: large stick deflections fly rates
        if attitude_enabled:
            self._attitude(q, mode, sticks, stick_setpoint, dt)
        elif mode.flag_control_manual_enabled and mode.flag_control_rates_enabled and sticks is not None:
            self.shaping.release()
            rates = self.acro.rates(sticks.roll, sticks.pitch, sticks.yaw)
            thrust = AcroStickMapping.thrust_body(sticks.throttle)
            self.publish(
                ORB_ID.vehicle_rates_setpoint,
                VehicleRatesSetpoint(roll=rates[0], pitch=rates[1], yaw=rates[2], thrust_body=thrust),
            )
        else:
            self.shaping.release()

    def _attitude(
        self,
        q: tuple[float, float, float, float],
        mode: VehicleControlMode,
        sticks,
        setpoint: VehicleAttitudeSetpoint | None,
        dt: float,
    ) -> None:
        """Rates from the attitude setpoint: Stabilized's from the sticks (``setpoint``), the RotorS mode's, or the
        one on the bus."""
        if setpoint is not None:
            self.publish(ORB_ID.vehicle_attitude_setpoint, setpoint)
        elif mode.flag_control_rpyt_enabled and sticks is not None:
            setpoint = self._rotors(q, sticks, mode.flag_armed, dt)
        else:
            setpoint = self.latest(ORB_ID.vehicle_attitude_setpoint)
        if not mode.flag_control_rpyt_enabled:
            self._rotors_heading = None
        if setpoint is None or not quat.is_finite(setpoint.q_d):
            return
        rates = self.shaping.rates(self.control, setpoint.q_d, setpoint.yaw_sp_move_rate, q, self._body_rates(), dt)
        self.publish(
            ORB_ID.vehicle_rates_setpoint,
            VehicleRatesSetpoint(roll=rates[0], pitch=rates[1], yaw=rates[2], thrust_body=setpoint.thrust_body),
        )

    def _rotors(self, q: tuple[float, float, float, float], sticks, armed: bool, dt: float) -> VehicleAttitudeSetpoint:
        """The RotorS mode's setpoint. RotorS' own law keeps the current heading and damps the yaw rate towards the
        command; PX4's attitude loop follows a heading, so the commanded rate moves one along from the current."""
        command = self.joy.command(sticks.roll, sticks.pitch, sticks.yaw, sticks.throttle)
        heading = self._rotors_heading
        self._rotors_heading = quat.yaw(q) if heading is None or not armed else wrap_pi(heading + command.yaw_rate * dt)
        self.publish(
            ORB_ID.roll_pitch_yawrate_thrust_setpoint,
            RollPitchYawrateThrustSetpoint(
                timestamp_sample=sticks.timestamp_sample,
                roll=command.roll,
                pitch=command.pitch,
                yaw_rate=command.yaw_rate,
                thrust=command.thrust,
            ),
        )
        sp = rotors_attitude_setpoint(self._rotors_heading, command, self._thrust_max)
        setpoint = VehicleAttitudeSetpoint(yaw_sp_move_rate=sp.yaw_sp_move_rate, q_d=sp.q_d, thrust_body=sp.thrust_body)
        self.publish(ORB_ID.vehicle_attitude_setpoint, setpoint)
        return setpoint

    def _body_rates(self) -> tuple[float, float, float]:
        """Measured body rates: at large tilt errors the shaper's yaw demand blends toward the yaw rate."""
        rates = self.latest(ORB_ID.vehicle_angular_velocity)
        return (0.0, 0.0, 0.0) if rates is None else rates.xyz
