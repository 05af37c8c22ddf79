"""Motor output stage: thrust model, slew limit, armed/disarmed PWM and the simulator view."""

import math

import pytest

from stack.mixer.output import MotorOutput, command_from_thrust, thrust_from_command


@pytest.mark.parametrize("factor", [0.0, 0.3, 0.65, 1.0])
def test_thrust_model_round_trip(factor):
    for thrust in (0.0, 0.01, 0.25, 0.5, 0.9, 1.0):
        u = command_from_thrust(thrust, factor)
        assert 0.0 <= u <= 1.0 + 1e-12
        assert thrust_from_command(u, factor) == pytest.approx(thrust, abs=1e-12)


def test_quadratic_thrust_model_takes_the_square_root():
    assert command_from_thrust(0.25, 1.0) == pytest.approx(0.5)
    assert command_from_thrust(0.25, 0.0) == 0.25


def test_disarmed_stops_every_motor():
    out = MotorOutput(4).update([0.5, 0.5, 0.5, 0.5], armed=False, dt=0.004)
    assert all(math.isnan(m) for m in out.actuator_motors)
    assert out.pwm == (900.0,) * 4
    assert out.sim == (0.0,) * 4


def test_armed_zero_command_idles_and_full_command_is_max():
    out = MotorOutput(4).update([0.0, 1.0, 0.5, 0.0], armed=True, dt=0.004)
    assert out.actuator_motors == (0.0, 1.0, 0.5, 0.0)
    assert out.pwm == pytest.approx((1075.0, 2000.0, 1075.0 + 0.5 * 925.0, 1075.0))
    assert out.sim == pytest.approx((0.075, 1.0, (1075.0 + 0.5 * 925.0 - 1000.0) / 1000.0, 0.075))


def test_thrust_model_is_applied_before_the_pwm_mapping():
    out = MotorOutput(1, {"THR_MDL_FAC": 1.0, "PWM_MAIN_MIN": 1000}).update([0.25], armed=True, dt=0.004)
    assert out.pwm == pytest.approx((1500.0,))
    assert out.sim == pytest.approx((0.5,))
    assert out.actuator_motors == (0.25,)


def test_stopped_motor_while_armed():
    out = MotorOutput(2).update([math.nan, -0.5], armed=True, dt=0.004)
    assert all(math.isnan(m) for m in out.actuator_motors)
    assert out.pwm == (900.0, 900.0) and out.sim == (0.0, 0.0)


def test_slew_limit_per_motor():
    stage = MotorOutput(2, {"CA_R0_SLEW": 0.5})
    for k in range(1, 6):
        out = stage.update([1.0, 1.0], armed=True, dt=0.01)
        assert out.actuator_motors[0] == pytest.approx(0.02 * k)
        assert out.actuator_motors[1] == 1.0
    down = stage.update([0.0, 0.0], armed=True, dt=0.01)
    assert down.actuator_motors == pytest.approx((0.08, 0.0))
    # Disarming clears the memory: after re-arming the ramp starts from zero.
    stage.update([1.0, 1.0], armed=False, dt=0.01)
    assert stage.update([1.0, 1.0], armed=True, dt=0.01).actuator_motors[0] == pytest.approx(0.02)
