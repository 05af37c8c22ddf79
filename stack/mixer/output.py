"""Motor output stage: allocated motor thrusts → actuator_motors, PWM and the simulator's view.

Follows PX4's output path: the per-motor slew limit (CA_R<n>_SLEW, applied by ControlAllocator), the
thrust model THR_MDL_FAC of ``mixer_module/functions/FunctionMotors`` (normalised thrust → motor
command), the armed/disarmed PWM mapping of ``MixingOutput`` (PWM_MAIN_MIN/MAX/DIS) and the rescaling
of ``simulation/pwm_out_sim/PWMSim.cpp`` into ``actuator_outputs_sim``.

Idle: PWM_MAIN_MIN defaults to 1075 µs here, not PX4's 1000 µs, so that a zero command from an armed
vehicle spins the motors at 7.5 % of the ESC range (PX4's documented practice of raising PWM_MIN until
the motors idle reliably; PX4's own legacy multicopter scripts used 1075, and DShot's DSHOT_MIN 0.055
plays the same role). The simulator view keeps the fixed ESC calibration range [1000, 2000] µs → [0, 1],
so the idle is visible to the simulated motors; disarmed outputs (PWM_MAIN_DIS) read 0 there, as in
pwm_out_sim, which leaves them unwritten.

A plane's motor has no idle: its idle is a throttle (FW_THR_IDLE) the position controller commands, so a zero
throttle stops the motor (the ESC range's 1000 µs; PX4's fixed-wing outputs start at 1000 µs). Control surfaces are
servos centred at 1500 µs, ±500 µs at full deflection (PX4's servo defaults), their simulator view the command
itself in [−1, 1]; disarmed they are centred.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

from stack.mathlib.scalar import FLT_EPSILON
from stack.params import ca
from stack.params.binding import ParamSet, combine, with_defaults
from stack.params.param import Param


class MotorOutputParams(ParamSet):
    """The thrust curve and the PWM range (the motors' slew limits are the CA_R<n>_SLEW family)."""

    thr_mdl_fac: float
    pwm_main_dis: int
    pwm_main_min: int
    pwm_main_max: int


PARAMS: tuple[Param, ...] = combine(MotorOutputParams.PARAMS, ca.SLEW_PARAMS)

ESC_RANGE_MIN_US = 1000.0
"""ESC calibration endpoints: the pulse widths the simulator reads as 0 and 1 (pwm_out_sim's range)."""
ESC_RANGE_MAX_US = 2000.0
SERVO_CENTRE_US = 1500.0
"""A control surface's pulse width at zero deflection."""
SERVO_HALF_RANGE_US = 500.0
"""Pulse-width change from the centre to full deflection."""


def command_from_thrust(thrust: float, factor: float) -> float:
    """Motor command u for a normalised thrust, inverting thrust = f·u² + (1−f)·u (f = THR_MDL_FAC)."""
    if factor <= 0.0 or factor > 1.0:
        return thrust
    b = 1.0 - factor
    tmp1 = b / (2.0 * factor)
    tmp2 = b * b / (4.0 * factor * factor)
    if thrust > 0.0:
        return -tmp1 + math.sqrt(tmp2 + thrust / factor)
    if thrust < 0.0:
        return tmp1 - math.sqrt(tmp2 - thrust / factor)
    return 0.0


def thrust_from_command(command: float, factor: float) -> float:
    """Normalised thrust of motor command u ≥ 0 under the THR_MDL_FAC model."""
    return factor * command * command + (1.0 - factor) * command


class MotorOutputs(NamedTuple):
    actuator_motors: tuple[float, ...]
    """Normalised thrust after the slew limit, [0, 1]; NaN = motor stopped (disarmed or not commanded)."""
    pwm: tuple[float, ...]
    """Pulse widths [µs]: PWM_MAIN_DIS when stopped, PWM_MAIN_MIN … PWM_MAIN_MAX when armed."""
    sim: tuple[float, ...]
    """actuator_outputs_sim: the PWM on the ESC range [1000, 2000] µs → [0, 1]; stopped motors 0."""


class MotorOutput:
    """Stateful output stage for N motors (the slew limits remember the last thrusts)."""

    __slots__ = ("_factor", "_idle", "_prev", "_pwm_dis", "_pwm_max", "_pwm_min", "_slew_time")

    def __init__(self, num_motors: int, params: Mapping[str, object] | None = None, *, idle: bool = True) -> None:
        """``idle``: an armed zero command spins the motors at PWM_MAIN_MIN (multirotors); without, it stops them
        at the ESC range's minimum (a plane)."""
        self._prev = [0.0] * num_motors
        self._idle = idle
        self.set_params(params or {})

    def set_params(self, params: Mapping[str, object]) -> None:
        p = MotorOutputParams.from_params(params)
        slew = with_defaults(ca.SLEW_PARAMS, params)
        self._factor = p.thr_mdl_fac
        self._slew_time = [float(slew[f"CA_R{i}_SLEW"]) for i in range(len(self._prev))]  # type: ignore[arg-type]
        self._pwm_dis = float(p.pwm_main_dis)
        self._pwm_min = float(p.pwm_main_min) if self._idle else ESC_RANGE_MIN_US
        self._pwm_max = float(p.pwm_main_max)

    def update(self, thrusts: Sequence[float], armed: bool, dt: float) -> MotorOutputs:
        """Map allocated motor thrusts (normalised, [0, 1]; NaN or < 0 stops that motor) to the outputs."""
        n = len(self._prev)
        if not armed:
            self._prev = [0.0] * n
            return MotorOutputs((math.nan,) * n, (self._pwm_dis,) * n, (0.0,) * n)
        motors, pwm, sim = [], [], []
        span = self._pwm_max - self._pwm_min
        for i in range(n):
            t = thrusts[i]
            if not t >= -FLT_EPSILON:
                self._prev[i] = 0.0
                motors.append(math.nan)
                pwm.append(self._pwm_dis)
                sim.append(0.0)
                continue
            prev = self._prev[i]
            slew_time = self._slew_time[i]
            max_step = dt / slew_time if slew_time > 0.0 else math.inf
            t = min(max(t, prev - max_step, 0.0), prev + max_step, 1.0)
            self._prev[i] = t
            u = min(max(command_from_thrust(t, self._factor), 0.0), 1.0)
            us = self._pwm_min + u * span
            motors.append(t)
            pwm.append(us)
            sim.append(min(max((us - ESC_RANGE_MIN_US) / (ESC_RANGE_MAX_US - ESC_RANGE_MIN_US), 0.0), 1.0))
        return MotorOutputs(tuple(motors), tuple(pwm), tuple(sim))


class ServoOutputs(NamedTuple):
    actuator_servos: tuple[float, ...]
    """Surface commands in [−1, 1] (0 when disarmed)."""
    pwm: tuple[float, ...]
    """Pulse widths [µs]: 1500 ± 500 at full deflection, 1500 when disarmed."""
    sim: tuple[float, ...]
    """actuator_outputs_sim: the command in [−1, 1], 0 when disarmed."""


def servo_outputs(servos: Sequence[float], armed: bool) -> ServoOutputs:
    """The outputs of control-surface commands (non-finite ones centred)."""
    commands = tuple(min(max(u, -1.0), 1.0) if armed and math.isfinite(u) else 0.0 for u in servos)
    return ServoOutputs(commands, tuple(SERVO_CENTRE_US + u * SERVO_HALF_RANGE_US for u in commands), commands)
