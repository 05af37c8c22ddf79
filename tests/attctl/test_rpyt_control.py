"""RotorS' roll-pitch-yawrate-thrust controller: its error terms, its allocation on the hexa and the quads, and the
PX4 attitude setpoints made RotorS commands, against hand-worked cases."""

import math

import pytest

from stack.airframe.model import load_vehicle
from stack.attctl.rotors_joy import RollPitchYawrateThrust
from stack.attctl.rpyt_control import RollPitchYawrateThrustControl, allocation_matrix, zxy, zxy_angles
from stack.attctl.rpyt_setpoints import command_from_attitude, thrust_newtons
from stack.mathlib import quaternion as quat

G = 9.80665
# The rotor data as RotorS gives it (rotors_description/urdf/<mav>.xacro): k_f [N/(rad/s)²], ω_max [rad/s], k_m
# [m], arm length l [m].
ROTORS = {
    "firefly": (8.54858e-06, 838.0, 0.016, 0.215),
    "hummingbird": (8.54858e-06, 838.0, 0.016, 0.17),
    "pelican": (9.9865e-06, 838.0, 0.016, 0.21),
}
LEVEL = quat.IDENTITY
STILL = (0.0, 0.0, 0.0)
PHI = math.radians(10.0)


def controller(name: str = "firefly") -> RollPitchYawrateThrustControl:
    return RollPitchYawrateThrustControl(load_vehicle(name))


def rotor_thrusts(name: str, motors: tuple[float, ...]) -> list[float]:
    """k_f·ω² per rotor, with ω = u·ω_max as the simulated motors turn."""
    k_f, w_max, _, _ = ROTORS[name]
    return [k_f * (u * w_max) ** 2 for u in motors]


def hover(name: str) -> float:
    return load_vehicle(name).mass * G


# -- error terms ------------------------------------------------------------------------------------------------


def test_a_roll_command_from_level_is_an_attitude_error_of_minus_sin_roll_about_x():
    control = controller()
    control.set_command(RollPitchYawrateThrust(PHI, 0.0, 0.0, 10.0))
    e_r, e_w = control.errors(LEVEL, STILL)
    assert e_r == pytest.approx((-math.sin(PHI), 0.0, 0.0), abs=1e-12)
    assert e_w == pytest.approx(STILL, abs=1e-12)


def test_a_pitch_command_nose_up_is_an_error_about_y_of_the_same_form():
    control = controller()
    control.set_command(RollPitchYawrateThrust(0.0, PHI, 0.0, 10.0))
    assert control.errors(LEVEL, STILL)[0] == pytest.approx((0.0, -math.sin(PHI), 0.0), abs=1e-12)


@pytest.mark.parametrize("heading", [0.0, 1.0, -2.5, math.pi])
def test_the_heading_is_always_the_current_one_so_a_vehicle_at_the_commanded_tilt_has_no_error(heading):
    control = controller()
    control.set_command(RollPitchYawrateThrust(PHI, 0.0, 0.0, 10.0))
    at_roll = quat.from_euler(PHI, 0.0, heading)
    assert control.errors(at_roll, STILL)[0] == pytest.approx(STILL, abs=1e-12)
    control.set_command(RollPitchYawrateThrust(0.0, -PHI, 0.0, 10.0))
    at_pitch = quat.from_euler(0.0, -PHI, heading)
    assert control.errors(at_pitch, STILL)[0] == pytest.approx(STILL, abs=1e-12)


def test_the_rate_error_is_the_body_rate_less_the_yaw_rate_about_the_desired_z_axis():
    control = controller()
    control.set_command(RollPitchYawrateThrust(0.0, 0.0, 0.5, 10.0))  # 0.5 rad/s clockwise seen from above
    assert control.errors(quat.from_euler(0.0, 0.0, 0.7), (0.1, 0.2, 0.3))[1] == pytest.approx((0.1, 0.2, -0.2))
    # Off the setpoint RotorS maps the yaw rate by R_dᵀR (level vehicle, roll φ asked): (0, sin φ, cos φ)·r.
    control.set_command(RollPitchYawrateThrust(PHI, 0.0, 0.5, 10.0))
    e_w = control.errors(LEVEL, (0.1, 0.2, 0.3))[1]
    assert e_w == pytest.approx((0.1, 0.2 - 0.5 * math.sin(PHI), 0.3 - 0.5 * math.cos(PHI)))


def test_the_law_turns_the_errors_into_torques_minus_gain_times_error():
    """α = −(K_R/I)∘e_R − (K_ω/I)∘e_ω, and the allocation gives back I·α: a torque −K_R·e_R − K_ω·e_ω."""
    name = "hummingbird"
    control = controller(name)
    gains = {"RPYT_ATT_GAIN_X": 0.7, "RPYT_RATE_GAIN_X": 0.1}
    control.set_params(gains)
    control.set_command(RollPitchYawrateThrust(PHI, 0.0, 0.0, hover(name)))
    thrusts = rotor_thrusts(name, control.motors(LEVEL, (0.2, 0.0, 0.0)))
    arm = ROTORS[name][3]
    roll_torque = (thrusts[1] - thrusts[3]) * arm  # rotor 1 on the left, 3 on the right
    assert roll_torque == pytest.approx(0.7 * math.sin(PHI) - 0.1 * 0.2)


# -- allocation -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(ROTORS))
def test_a_pure_thrust_demand_turns_every_rotor_equally_and_the_thrusts_add_up(name):
    control = controller(name)
    thrust = hover(name)
    motors = control.allocate(STILL, thrust)
    assert max(motors) == pytest.approx(min(motors))
    assert sum(rotor_thrusts(name, motors)) == pytest.approx(thrust)
    assert motors[0] == pytest.approx(load_vehicle(name).hover_command)


@pytest.mark.parametrize("name", ["hummingbird", "pelican"])
def test_on_a_plus_quad_a_roll_demand_moves_the_side_rotors_only(name):
    """FRD roll + lifts the left side: rotor 1 (left) takes I_xx·α/(2l) more, rotor 3 (right) as much less."""
    vehicle = load_vehicle(name)
    thrust, alpha, arm = hover(name), 20.0, ROTORS[name][3]
    thrusts = rotor_thrusts(name, controller(name).allocate((alpha, 0.0, 0.0), thrust))
    delta = vehicle.inertia[0] * alpha / (2.0 * arm)
    assert thrusts == pytest.approx([thrust / 4, thrust / 4 + delta, thrust / 4, thrust / 4 - delta])


@pytest.mark.parametrize("name", ["hummingbird", "pelican"])
def test_on_a_plus_quad_a_pitch_demand_nose_up_speeds_up_the_front_rotor(name):
    vehicle = load_vehicle(name)
    thrust, alpha, arm = hover(name), 20.0, ROTORS[name][3]
    thrusts = rotor_thrusts(name, controller(name).allocate((0.0, alpha, 0.0), thrust))
    delta = vehicle.inertia[1] * alpha / (2.0 * arm)
    assert thrusts == pytest.approx([thrust / 4 + delta, thrust / 4, thrust / 4 - delta, thrust / 4])


@pytest.mark.parametrize("name", list(ROTORS))
def test_a_yaw_demand_clockwise_speeds_up_the_counter_clockwise_rotors(name):
    """Each counter-clockwise rotor's drag turns the body clockwise: k_m·ΔT per rotor, I_zz·α in all."""
    vehicle = load_vehicle(name)
    thrust, alpha, k_m = hover(name), 2.0, ROTORS[name][2]
    thrusts = rotor_thrusts(name, controller(name).allocate((0.0, 0.0, alpha), thrust))
    n = vehicle.rotor_count
    delta = vehicle.inertia[2] * alpha / (n * k_m)
    assert thrusts == pytest.approx([thrust / n + r.spin * delta for r in vehicle.rotors])


def test_on_the_hexa_a_roll_demand_shares_the_torque_in_proportion_to_each_arm_s_reach():
    """The least-squares split: ΔT_i = I_xx·α·y_i/Σy², y_i the rotor's distance to the left (Σy² = 3l²)."""
    vehicle = load_vehicle("firefly")
    thrust, alpha, arm = hover("firefly"), 20.0, ROTORS["firefly"][3]
    thrusts = rotor_thrusts("firefly", controller().allocate((alpha, 0.0, 0.0), thrust))
    lefts = [-r.position[1] for r in vehicle.rotors]
    expected = [thrust / 6 + vehicle.inertia[0] * alpha * y / (3.0 * arm * arm) for y in lefts]
    assert thrusts == pytest.approx(expected)
    assert thrusts[1] > thrusts[0] > thrusts[5] > thrusts[4]  # left > front-left > front-right > right


def test_the_allocation_rows_are_rotors_own():
    """A's columns (sinγ·l·k_f, −cosγ·l·k_f, −dir·k_f·k_m, k_f) in thrust-fraction units (k_f·ω_max²)."""
    k_f, w_max, k_m, arm = ROTORS["hummingbird"]
    full = k_f * w_max * w_max
    a = allocation_matrix(load_vehicle("hummingbird"))
    # rotor 0 front (γ = 0, CW: dir −1), rotor 1 left (γ = 90°, CCW: dir +1)
    assert a[:, 0] == pytest.approx([0.0, -arm * full, k_m * full, full], rel=1e-3, abs=1e-12)
    assert a[:, 1] == pytest.approx([arm * full, 0.0, -k_m * full, full], rel=1e-3, abs=1e-12)


def test_the_motor_commands_stay_in_zero_to_one():
    control = controller()
    assert control.allocate(STILL, 1e6) == (1.0,) * 6
    assert control.allocate(STILL, -5.0) == (0.0,) * 6
    one_side = control.allocate((1e4, 0.0, 0.0), hover("firefly"))
    assert min(one_side) == 0.0 and max(one_side) == 1.0


# -- commands ---------------------------------------------------------------------------------------------------


def test_the_rotors_stand_still_until_the_first_command_and_after_a_reset():
    control = controller()
    assert control.motors(LEVEL, STILL) == (0.0,) * 6 and control.thrust == 0.0
    control.set_command(RollPitchYawrateThrust(0.0, 0.0, 0.0, hover("firefly")))
    assert min(control.motors(LEVEL, STILL)) > 0.6
    control.reset()
    assert control.motors(LEVEL, STILL) == (0.0,) * 6


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_command_that_is_not_finite_is_refused_and_the_last_good_one_kept(bad):
    control = controller()
    good = RollPitchYawrateThrust(PHI, 0.0, 0.0, hover("firefly"))
    assert control.set_command(good)
    before = control.motors(LEVEL, STILL)
    for field in range(4):
        values = list(good)
        values[field] = bad
        assert not control.set_command(RollPitchYawrateThrust(*values))
    assert not control.set_rates_command((0.0, bad if math.isinf(bad) else 0.0, 0.0), bad)
    assert control.motors(LEVEL, STILL) == before


def test_a_rate_command_has_no_attitude_term_and_nan_holds_an_axis():
    control = controller()
    control.set_rates_command((0.5, math.nan, -0.2), 10.0)
    e_r, e_w = control.errors(quat.from_euler(0.3, 0.2, 1.0), (0.1, 0.7, 0.1))
    assert e_r == (0.0, 0.0, 0.0)
    assert e_w == pytest.approx((-0.4, 0.0, 0.3))
    assert control.thrust == 10.0


def test_without_a_state_estimate_only_the_thrust_is_flown():
    control = controller()
    control.set_command(RollPitchYawrateThrust(PHI, 0.0, 0.3, hover("firefly")))
    assert control.motors((math.nan,) * 4, (math.nan,) * 3) == control.allocate(STILL, hover("firefly"))


# -- PX4 setpoints as RotorS commands -----------------------------------------------------------------------------


def test_zxy_angles_undo_zxy():
    assert zxy_angles(zxy(2.0, -0.4, 0.3)) == pytest.approx((2.0, -0.4, 0.3))
    assert zxy_angles(quat.to_dcm(quat.from_euler(0.0, 0.0, -1.2))) == pytest.approx((-1.2, 0.0, 0.0))


def test_an_attitude_setpoint_is_its_roll_and_pitch_and_a_yaw_rate_toward_its_heading():
    q = quat.from_euler(0.0, 0.0, 0.5)
    q_d = quat.from_dcm(zxy(0.7, 0.1, -0.2))
    command = command_from_attitude(q, q_d, 0.05, (0.0, 0.0, -0.4), 2.0, 36.0)
    assert command == pytest.approx(RollPitchYawrateThrust(0.1, -0.2, 0.05 + 2.0 * 0.2, 0.4 * 36.0))
    across = command_from_attitude(quat.from_euler(0.0, 0.0, 3.0), quat.from_euler(0.0, 0.0, -3.0), math.nan,
                                   (0.0, 0.0, -0.5), 1.0, 36.0)
    assert across.yaw_rate == pytest.approx(2.0 * math.pi - 6.0)  # the short way round; NaN feed-forward is none


def test_a_normalised_thrust_is_newtons_at_full_command_and_nan_when_not_finite():
    assert thrust_newtons((0.0, 0.0, -0.5), 36.0) == 18.0
    assert thrust_newtons((0.0, 0.0, -1.5), 36.0) == 36.0 and thrust_newtons((0.0, 0.0, 0.2), 36.0) == 0.0
    assert math.isnan(thrust_newtons((0.0, 0.0, math.inf), 36.0))
    command = command_from_attitude(LEVEL, (math.nan,) * 4, 0.0, (0.0, 0.0, -0.5), 1.0, 36.0)
    assert not controller().set_command(command)
