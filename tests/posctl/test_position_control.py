import math

import pytest

from stack.mathlib import quaternion
from stack.mathlib.scalar import CONSTANTS_ONE_G as G
from stack.mathlib.vector import NAN3, ZERO3
from stack.posctl.position_control import (
    PositionControl,
    PositionControlParams,
    failsafe_setpoint,
)

NAN = math.nan
DT = 0.01


def _run(pc, pos_sp=NAN3, vel_sp=NAN3, acc_sp=NAN3, *, pos=ZERO3, vel=ZERO3, vel_dot=ZERO3, yaw=0.0,
         yaw_sp=NAN, yawspeed_sp=NAN, dt=DT):
    pc.set_state(pos, vel, vel_dot, yaw)
    pc.set_setpoint(pos_sp, vel_sp, acc_sp, yaw_sp, yawspeed_sp)
    return pc.update(dt)


def _tilt(thrust):
    return math.atan2(math.hypot(thrust[0], thrust[1]), -thrust[2])


def test_hover_at_setpoint_gives_hover_thrust_and_yaw():
    pc = PositionControl()
    assert _run(pc, (1.0, 2.0, -3.0), pos=(1.0, 2.0, -3.0), yaw_sp=0.8)
    assert pc.thrust_setpoint == pytest.approx((0.0, 0.0, -0.5))
    q_d, thrust_body, yaw_rate = pc.attitude_setpoint()
    assert thrust_body == pytest.approx((0.0, 0.0, -0.5))
    assert quaternion.angle_between(q_d, quaternion.from_euler(0.0, 0.0, 0.8)) < 1e-9
    assert yaw_rate == 0.0


def test_position_and_velocity_gains_hand_worked():
    pc = PositionControl()
    assert _run(pc, (1.0, 0.0, -1.0))
    sp = pc.local_position_setpoint()
    assert sp.velocity == pytest.approx((0.95, 0.0, -1.0))
    assert sp.acceleration == pytest.approx((1.8 * 0.95, 0.0, -4.0))
    # T_z = a_z·Th/g − Th, projected on the (untilted by a_z: decoupled) body z axis.
    tz = -4.0 * 0.5 / G - 0.5
    assert pc.thrust_setpoint[2] == pytest.approx(tz)
    assert pc.thrust_setpoint[0] / -pc.thrust_setpoint[2] == pytest.approx(1.71 / G)


def test_d_term_acts_on_the_velocity_derivative_input():
    pc = PositionControl()
    assert _run(pc, vel_sp=(0.0, 0.0, 0.0), vel_dot=(1.0, -2.0, 0.5))
    assert pc.local_position_setpoint().acceleration == pytest.approx((-0.2, 0.4, 0.0))


def test_velocity_feed_forward_adds_to_the_position_term():
    pc = PositionControl()
    assert _run(pc, (1.0, 0.0, 0.0), (0.5, 0.5, 0.2))
    assert pc.local_position_setpoint().velocity == pytest.approx((1.45, 0.5, 0.2))


def test_nan_position_means_pure_velocity_control():
    pc = PositionControl()
    assert _run(pc, NAN3, (1.0, 0.0, 0.0), pos=NAN3)
    assert pc.local_position_setpoint().velocity == pytest.approx((1.0, 0.0, 0.0))


def test_acceleration_only_axis_needs_no_state_estimate():
    pc = PositionControl()
    assert _run(pc, (0.0, 0.0, NAN), NAN3, (NAN, NAN, 1.0), pos=(0.0, 0.0, NAN), vel=(0.0, 0.0, NAN))
    sp = pc.local_position_setpoint()
    assert sp.acceleration[2] == 1.0
    assert pc.thrust_setpoint[2] == pytest.approx(1.0 * 0.5 / G - 0.5)


def test_acceleration_feed_forward_is_added_to_the_pid_output():
    pc = PositionControl()
    assert _run(pc, vel_sp=(1.0, 0.0, 0.0), acc_sp=(0.5, 0.0, 0.0))
    assert pc.local_position_setpoint().acceleration[0] == pytest.approx(0.5 + 1.8)


@pytest.mark.parametrize(
    ("pos_sp", "vel_sp", "acc_sp"),
    [
        ((NAN, NAN, NAN), (NAN, NAN, 0.0), NAN3),  # no horizontal setpoint at all
        ((0.0, 0.0, NAN), NAN3, NAN3),  # no vertical setpoint
        ((0.0, NAN, 0.0), NAN3, NAN3),  # x without y (position)
        (NAN3, (0.0, NAN, 0.0), NAN3),  # x without y (velocity)
        ((0.0, 0.0, 0.0), NAN3, (1.0, NAN, NAN)),  # x without y (acceleration)
    ],
)
def test_invalid_setpoints_are_rejected(pos_sp, vel_sp, acc_sp):
    assert not _run(PositionControl(), pos_sp, vel_sp, acc_sp)


def test_controlled_state_without_estimate_is_rejected():
    assert not _run(PositionControl(), (0.0, 0.0, 0.0), pos=(NAN, NAN, 0.0))
    assert not _run(PositionControl(), vel_sp=ZERO3, vel=(0.0, 0.0, NAN))
    assert not _run(PositionControl(), vel_sp=ZERO3, vel_dot=(NAN, 0.0, 0.0))


def test_horizontal_speed_limit_keeps_the_position_term():
    pc = PositionControl()
    # 100 m away with a sideways feed-forward: the P term alone saturates the 12 m/s limit.
    assert _run(pc, (100.0, 0.0, 0.0), (0.0, 5.0, 0.0))
    assert pc.local_position_setpoint().velocity[:2] == pytest.approx((12.0, 0.0))
    # 10 m away (P term 9.5 m/s): the feed-forward only fills up to the limit.
    assert _run(pc, (10.0, 0.0, 0.0), (0.0, 20.0, 0.0))
    vx, vy, _ = pc.local_position_setpoint().velocity
    assert vx == pytest.approx(9.5)
    assert math.hypot(vx, vy) == pytest.approx(12.0)


def test_vertical_speed_limits():
    pc = PositionControl()
    assert _run(pc, (0.0, 0.0, -50.0))
    assert pc.local_position_setpoint().velocity[2] == pytest.approx(-3.0)
    assert _run(pc, (0.0, 0.0, 50.0))
    assert pc.local_position_setpoint().velocity[2] == pytest.approx(1.5)


def test_tilt_is_limited():
    pc = PositionControl()
    assert _run(pc, acc_sp=(30.0, 10.0, 0.0), pos_sp=(NAN, NAN, 0.0))
    assert _tilt(pc.thrust_setpoint) == pytest.approx(math.radians(45.0))
    q_d, _, _ = pc.attitude_setpoint()
    assert math.acos(quaternion.dcm_z(q_d)[2]) == pytest.approx(math.radians(45.0))
    pc.set_limits(tilt_max=math.radians(20.0))
    assert _run(pc, acc_sp=(30.0, 10.0, 0.0), pos_sp=(NAN, NAN, 0.0))
    assert _tilt(pc.thrust_setpoint) == pytest.approx(math.radians(20.0))


def test_vertical_thrust_has_priority_with_horizontal_margin():
    pc = PositionControl()
    # Large climb and moderate horizontal demand: vertical keeps all but the 0.3 margin.
    assert _run(pc, acc_sp=(2.0, 0.0, -30.0), pos_sp=(NAN, NAN, NAN))
    tx, ty, tz = pc.thrust_setpoint
    assert tz == pytest.approx(-math.sqrt(1.0 - 0.3**2))
    assert math.hypot(tx, ty) == pytest.approx(0.3)
    # Small horizontal demand (below the margin): it is served fully, vertical takes the rest.
    assert _run(pc, acc_sp=(0.3, 0.0, -30.0), pos_sp=(NAN, NAN, NAN))
    tx, ty, tz = pc.thrust_setpoint
    # Requested horizontal thrust: tan(tilt)·|T_z| with tan(tilt) = a_x/g.
    assert math.hypot(tx, ty) == pytest.approx(0.3 / G * (30.0 * 0.5 / G + 0.5))
    assert tz == pytest.approx(-math.sqrt(1.0 - tx * tx))


def test_thrust_never_below_minimum():
    pc = PositionControl()
    assert _run(pc, acc_sp=(0.0, 0.0, 50.0), pos_sp=(0.0, 0.0, NAN))
    assert pc.thrust_setpoint[2] == pytest.approx(-0.12)


def test_acceleration_decoupling():
    decoupled = PositionControl()
    coupled = PositionControl(PositionControlParams(mpc_acc_decouple=False))
    for pc in (decoupled, coupled):
        assert _run(pc, acc_sp=(2.0, 0.0, -3.0), pos_sp=(NAN, NAN, NAN))
    assert _tilt(decoupled.thrust_setpoint) == pytest.approx(math.atan(2.0 / G))
    assert _tilt(coupled.thrust_setpoint) == pytest.approx(math.atan(2.0 / (G + 3.0)))
    # Both keep the same vertical thrust component.
    assert decoupled.thrust_setpoint[2] == pytest.approx(coupled.thrust_setpoint[2])


def test_vertical_anti_windup_at_max_thrust():
    pc = PositionControl()
    # Asking to climb far faster than possible saturates at max thrust: no integration upward.
    for _ in range(100):
        assert _run(pc, vel_sp=(0.0, 0.0, -3.0), acc_sp=(NAN, NAN, -40.0), vel=(0.0, 0.0, 0.0))
    assert pc.thrust_setpoint[2] == pytest.approx(-1.0)
    assert pc.velocity_integral[2] == 0.0


def test_vertical_anti_windup_at_min_thrust():
    pc = PositionControl()
    for _ in range(100):
        assert _run(pc, vel_sp=(0.0, 0.0, 1.5), acc_sp=(NAN, NAN, 20.0))
    assert pc.thrust_setpoint[2] == pytest.approx(-0.12)
    assert pc.velocity_integral[2] == 0.0


def test_vertical_integrator_integrates_when_not_saturated():
    pc = PositionControl()
    assert _run(pc, vel_sp=(0.0, 0.0, 0.5))
    assert pc.velocity_integral[2] == pytest.approx(0.5 * 2.0 * DT)


def test_vertical_integrator_is_clamped_to_g():
    # Low hover thrust so that −g of integrator is still far from the thrust limit; P off.
    pc = PositionControl(PositionControlParams(mpc_thr_hover=0.3, mpc_z_vel_p_acc=0.0))
    for _ in range(3000):
        assert _run(pc, vel_sp=(0.0, 0.0, -0.5))
    assert pc.local_position_setpoint().acceleration[2] == pytest.approx(-G)
    assert pc.thrust_setpoint[2] == pytest.approx(-0.6)


def test_horizontal_tracking_anti_windup_limits_integrator_growth():
    steps = 3000
    plain_growth = 0.4 * 5.0 * steps * DT  # Ki·e·t without anti-windup
    pc = PositionControl()
    history = []
    for _ in range(steps):
        assert _run(pc, vel_sp=(5.0, 0.0, 0.0), pos_sp=(NAN, NAN, 0.0), vel=(0.0, 0.0, 0.0))
        history.append(pc.velocity_integral[0])
    # Tilt-saturated: produced a_x = g·tan(45°) but 9 m/s² + I requested. The tracking term
    # 2/Kp·(a_sp − a_produced) drives the integrator to where it cancels the error.
    assert _tilt(pc.thrust_setpoint) == pytest.approx(math.radians(45.0))
    assert history[-1] < 0.5 * plain_growth
    assert abs(history[-1] - history[-100]) < 1e-4
    # Equilibrium: e − 2/Kp·(Kp·e + I − a_prod) = 0 → I = a_prod − Kp·e/2.
    a_prod = pc.thrust_setpoint[0] * G / 0.5
    assert history[-1] == pytest.approx(a_prod - 1.8 * 5.0 / 2.0, abs=1e-3)


def test_hover_thrust_update_keeps_thrust_continuous():
    pc = PositionControl()
    inputs = dict(pos_sp=(0.0, 0.0, -2.0), vel_sp=(0.5, 0.0, -0.3), pos=(0.2, 0.1, -1.5), vel=(0.3, 0.0, -0.1))
    for _ in range(50):
        assert _run(pc, **inputs)
    assert _run(pc, **inputs, dt=0.0)
    before = pc.thrust_setpoint
    pc.update_hover_thrust(0.62)
    assert pc.hover_thrust == 0.62
    assert _run(pc, **inputs, dt=0.0)
    assert pc.thrust_setpoint == pytest.approx(before, abs=1e-12)
    pc.update_hover_thrust(0.41)
    assert _run(pc, **inputs, dt=0.0)
    assert pc.thrust_setpoint == pytest.approx(before, abs=1e-12)
    # Setting the hover thrust directly (no absorption) does produce a step.
    pc.set_hover_thrust(0.6)
    assert _run(pc, **inputs, dt=0.0)
    assert abs(pc.thrust_setpoint[2] - before[2]) > 0.05


def test_reset_integral():
    pc = PositionControl()
    for _ in range(10):
        _run(pc, vel_sp=(1.0, 1.0, 1.0))
    assert any(pc.velocity_integral)
    pc.reset_integral()
    assert pc.velocity_integral == (0.0, 0.0, 0.0)


def test_a_restart_resumes_the_integral_of_the_earlier_instance_and_refuses_garbage():
    earlier = PositionControl()
    for _ in range(10):
        _run(earlier, vel_sp=(1.0, -1.0, 0.5))
    restarted = PositionControl()
    assert restarted.resume_integral(list(earlier.velocity_integral))
    assert restarted.velocity_integral == earlier.velocity_integral
    for garbage in ([math.nan, 0.0, 0.0], [0.0, 0.0], [20.0, 0.0, 0.0], ["1", 0.0, 0.0], {"x": 1.0}, None):
        assert not restarted.resume_integral(garbage)
        assert restarted.velocity_integral == earlier.velocity_integral


def test_blind_horizontal_flight_keeps_leaning_into_the_learned_wind():
    pc = PositionControl()
    for _ in range(200):  # a steady northward velocity error stands for a wind from the north
        _run(pc, ZERO3, pos=ZERO3, vel=(-0.5, 0.0, 0.0))
    wind_lean = pc.velocity_integral[0]
    assert wind_lean == pytest.approx(2.0 * 0.5 * 0.4)  # seconds × error × MPC_XY_VEL_I_ACC
    # Velocity estimate lost: zero horizontal acceleration plus the frozen integrator.
    assert _run(pc, NAN3, (NAN, NAN, 0.7), (0.0, 0.0, NAN), pos=NAN3, vel=(NAN, NAN, 0.7))
    assert pc.local_position_setpoint().acceleration[:2] == pytest.approx((wind_lean, 0.0))
    assert pc.velocity_integral[0] == wind_lean


def test_yaw_falls_back_to_current_heading():
    pc = PositionControl()
    assert _run(pc, ZERO3, yaw=1.2, yaw_sp=NAN, yawspeed_sp=0.3)
    q_d, _, yaw_rate = pc.attitude_setpoint()
    assert quaternion.yaw(q_d) == pytest.approx(1.2)
    assert yaw_rate == 0.3
    assert pc.local_position_setpoint().yaw == 1.2


def test_failsafe_setpoints_follow_px4_order():
    stop = failsafe_setpoint((0.1, 0.2, 0.3), land_speed=0.7)
    assert stop.action == "stop and wait"
    assert stop.velocity == (0.0, 0.0, 0.0)
    assert all(math.isnan(c) for c in stop.position + stop.acceleration)

    blind_land = failsafe_setpoint((NAN, NAN, 0.3), land_speed=0.7)
    assert blind_land.action == "blind land"
    assert blind_land.acceleration[:2] == (0.0, 0.0)
    assert blind_land.velocity[2] == 0.7
    assert math.isnan(blind_land.velocity[0])

    blind_descent = failsafe_setpoint((NAN, NAN, NAN), land_speed=0.7)
    assert blind_descent.action == "blind descent"
    assert blind_descent.acceleration == (0.0, 0.0, 0.3)
    assert all(math.isnan(c) for c in blind_descent.velocity)


@pytest.mark.parametrize("vel", [(0.5, -0.2, 0.1), (NAN, NAN, 0.1), (NAN, NAN, NAN)])
def test_failsafe_setpoints_are_executable(vel):
    pc = PositionControl()
    fs = failsafe_setpoint(vel, land_speed=0.7)
    assert _run(pc, fs.position, fs.velocity, fs.acceleration, pos=NAN3, vel=vel, vel_dot=ZERO3)
    if math.isnan(vel[2]):
        # a_z = +0.3 m/s²: slightly less than hover thrust.
        assert -0.5 < pc.thrust_setpoint[2] < -0.48
