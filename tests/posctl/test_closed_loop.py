"""Closed-loop checks of PositionControl (+ PositionSmoothing, HoverThrustEstimator) on a point mass.

Plant: a point mass whose normalised thrust vector follows the commanded one (the attitude loop
assumed perfect, q_d·thrust_body) through a first-order lag; a = g·ẑ + T·g/Th_true − drag·v + wind.
The true hover thrust differs from MPC_THR_HOVER so the integrator (or the estimator) must work.
"""

import math

import pytest

from stack.mathlib import quaternion
from stack.mathlib.filters import LowPassFilter2p
from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.mathlib.vector import NAN3
from stack.posctl.hover_thrust_estimator import HoverThrustEstimator
from stack.posctl.position_control import PositionControl
from stack.posctl.position_smoothing import PositionSmoothing, PositionSmoothingParams

DT = 0.01
THRUST_TIME_CONSTANT = 0.05
TRUE_HOVER = 0.56
DRAG = 0.1
WIND_ACCEL = (0.4, -0.3, 0.0)


class PointMass:
    def __init__(self, position):
        self.position = position
        self.velocity = (0.0, 0.0, 0.0)
        self.thrust = (0.0, 0.0, -TRUE_HOVER)
        self.acceleration = (0.0, 0.0, 0.0)
        self._lpf = [LowPassFilter2p(1.0 / DT, 5.0) for _ in range(3)]  # MPC_VELD_LP
        self._last_velocity = self.velocity
        self.velocity_derivative = (0.0, 0.0, 0.0)

    def step(self, thrust_command):
        k = DT / (THRUST_TIME_CONSTANT + DT)
        self.thrust = tuple(t + k * (c - t) for t, c in zip(self.thrust, thrust_command, strict=True))
        gain = G / TRUE_HOVER
        self.acceleration = tuple(
            gain * t - DRAG * v + w + (G if i == 2 else 0.0)
            for i, (t, v, w) in enumerate(zip(self.thrust, self.velocity, WIND_ACCEL, strict=True))
        )
        self.velocity = tuple(v + a * DT for v, a in zip(self.velocity, self.acceleration, strict=True))
        self.position = tuple(p + v * DT for p, v in zip(self.position, self.velocity, strict=True))
        self.velocity_derivative = tuple(
            f.apply((v - v0) / DT) for f, v, v0 in zip(self._lpf, self.velocity, self._last_velocity, strict=True)
        )
        self._last_velocity = self.velocity


def _control_step(pc, plant, pos_sp, vel_sp=NAN3, acc_sp=NAN3, yaw_sp=0.0):
    pc.set_state(plant.position, plant.velocity, plant.velocity_derivative, 0.0)
    pc.set_setpoint(pos_sp, vel_sp, acc_sp, yaw_sp, math.nan)
    assert pc.update(DT)
    q_d, thrust_body, _ = pc.attitude_setpoint()
    plant.step(quaternion.rotate(q_d, thrust_body))


def test_holds_position_against_wind_and_wrong_hover_thrust():
    target = (3.0, -2.0, -10.0)
    plant = PointMass(target)
    pc = PositionControl()
    errors = []
    for _ in range(round(30.0 / DT)):
        _control_step(pc, plant, target)
        errors.append(math.dist(plant.position, target))
    assert max(errors) < 0.5
    assert max(errors[-round(5.0 / DT):]) < 0.01
    # The integrator has absorbed wind and the hover-thrust error.
    assert pc.velocity_integral[0] == pytest.approx(-WIND_ACCEL[0], abs=0.01)
    assert pc.velocity_integral[1] == pytest.approx(-WIND_ACCEL[1], abs=0.01)
    # Extra upward acceleration making up for the low hover-thrust parameter (NED: negative).
    assert pc.velocity_integral[2] == pytest.approx(-G * (TRUE_HOVER / 0.5 - 1.0), abs=0.01)


def test_follows_a_20_m_leg_with_bounded_tracking_error():
    start, end = (0.0, 0.0, -5.0), (20.0, 0.0, -5.0)
    plant = PointMass(start)
    pc = PositionControl()
    for _ in range(round(5.0 / DT)):  # settle the integrators in hover first
        _control_step(pc, plant, start)
    smoothing = PositionSmoothing(PositionSmoothingParams(nav_acc_rad=2.0))
    smoothing.reset(plant.position, plant.velocity, (0.0, 0.0, 0.0))
    tracking, crosstrack = [], []
    arrived_at = None
    t = 0.0
    while t < 20.0:
        point = smoothing.generate(DT, plant.position, (start, end, end), stop_at_target=True)
        _control_step(pc, plant, point.position, point.velocity, point.acceleration)
        t += DT
        tracking.append(math.dist(plant.position, point.position))
        crosstrack.append(math.hypot(plant.position[1], plant.position[2] + 5.0))
        if arrived_at is None and math.dist(plant.position, end) < 0.1:
            arrived_at = t
    assert max(tracking) < 0.3
    assert max(crosstrack) < 0.15
    assert arrived_at is not None and arrived_at < 12.0
    assert math.dist(plant.position, end) < 0.02
    assert math.hypot(*plant.velocity) < 0.02
    # The trajectory itself respects the cruise speed; the vehicle tracks it closely.
    assert max(abs(v) for v in plant.velocity) < 0.1


def test_hover_thrust_estimate_feeds_the_controller_without_thrust_jumps():
    target = (0.0, 0.0, -10.0)
    plant = PointMass(target)
    pc = PositionControl()
    estimator = HoverThrustEstimator()
    t_us = 0
    worst_step = 0.0
    previous = None
    for _ in range(round(30.0 / DT)):
        _control_step(pc, plant, target)
        t_us += round(DT * 1e6)
        estimate = estimator.update(
            t_us,
            armed=True,
            in_air=True,
            velocity=plant.velocity,
            acc_z=plant.acceleration[2],
            thrust_z=pc.thrust_setpoint[2],
        )
        if estimate.valid:
            pc.update_hover_thrust(estimate.hover_thrust)
        if previous is not None:
            worst_step = max(worst_step, abs(pc.thrust_setpoint[2] - previous))
        previous = pc.thrust_setpoint[2]
    assert estimator.valid
    assert pc.hover_thrust == pytest.approx(TRUE_HOVER, abs=0.01)
    # With the right hover thrust the vertical integrator only has to cancel the wind-free rest.
    assert abs(pc.velocity_integral[2]) < 0.2
    assert worst_step < 0.01
    assert math.dist(plant.position, target) < 0.01
