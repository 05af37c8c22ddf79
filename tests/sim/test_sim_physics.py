"""Rigid-body plant: hover, free fall, drag, ground contact, sign conventions, motor lag, RK4 accuracy."""

from __future__ import annotations

import math

import pytest

from stack.airframe.model import VehicleModel, load_vehicle
from stack.mathlib.quaternion import angle_between, from_euler, from_rotation_vector, mul, to_euler
from stack.mathlib.vector import cross
from stack.sim.physics import GROUND_TIP_RATE, MulticopterPhysics

G = 9.80665
DT = 0.001
ALL_VEHICLES = ["sih_quad", "hummingbird", "pelican", "firefly"]


def run(p: MulticopterPhysics, commands: tuple[float, ...], seconds: float, wind=(0.0, 0.0, 0.0), dt: float = DT):
    for _ in range(round(seconds / dt)):
        p.step(dt, commands, wind)


def px4_thrust_curve(u: float, thr_mdl_fac: float) -> float:
    """PX4's THR_MDL_FAC model: relative thrust for a relative motor command."""
    return thr_mdl_fac * u * u + (1.0 - thr_mdl_fac) * u


def command_for_thrust(t: float, thr_mdl_fac: float) -> float:
    """Inverse of ``px4_thrust_curve`` (what PX4's output stage sends for a normalised thrust)."""
    if thr_mdl_fac == 0.0:
        return t
    a = (1.0 - thr_mdl_fac) / (2.0 * thr_mdl_fac)
    return -a + math.sqrt(a * a + t / thr_mdl_fac)


def effectiveness(model: VehicleModel) -> list[tuple[float, float, float, float]]:
    """Per rotor (τx, τy, τz, Fz) per unit normalised thrust, built from the [airframe] CA_* table only,
    as PX4 ActuatorEffectivenessRotors does: moment CT·(p × a) − CT·KM·a, thrust CT·a, a = (0, 0, −1)."""
    af = model.airframe
    columns = []
    for i in range(int(af["CA_ROTOR_COUNT"])):
        p = (af[f"CA_ROTOR{i}_PX"], af[f"CA_ROTOR{i}_PY"], af[f"CA_ROTOR{i}_PZ"])
        ct, km = af[f"CA_ROTOR{i}_CT"], af[f"CA_ROTOR{i}_KM"]
        axis = (0.0, 0.0, -1.0)
        m = cross(p, axis)
        columns.append((ct * m[0] - ct * km * axis[0], ct * m[1] - ct * km * axis[1], ct * m[2] - ct * km * axis[2],
                        ct * axis[2]))
    return columns


@pytest.mark.parametrize("name", ALL_VEHICLES)
def test_hover_at_mpc_thr_hover_holds_altitude_open_loop(name: str) -> None:
    model = load_vehicle(name)
    af = model.airframe
    u = command_for_thrust(af["MPC_THR_HOVER"], af["THR_MDL_FAC"])
    commands = (u,) * model.rotor_count
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -10.0), motor_states=commands)
    p.step(DT, commands)
    assert abs(p.acceleration[2]) < 0.01
    assert p.specific_force == pytest.approx((0.0, 0.0, -G), abs=0.01)
    run(p, commands, 1.0)
    assert p.position[2] == pytest.approx(-10.0, abs=0.005)
    assert math.hypot(p.position[0], p.position[1]) < 1e-6
    assert not p.on_ground


@pytest.mark.parametrize("name", ALL_VEHICLES)
def test_px4_thrust_curve_matches_the_plant(name: str) -> None:
    """THR_MDL_FAC and CA_ROTOR_CT in the airframe table reproduce the plant's thrust at any command."""
    model = load_vehicle(name)
    af = model.airframe
    for u in (0.3, 0.6, 0.9):
        p = MulticopterPhysics(model, gravity=0.0)
        commands = (u,) * model.rotor_count
        p.reset(position=(0.0, 0.0, -10.0), motor_states=commands)
        p.step(1e-4, commands)
        thrust = -p.acceleration[2] * model.mass
        expected = model.rotor_count * af["CA_ROTOR0_CT"] * px4_thrust_curve(u, af["THR_MDL_FAC"])
        assert thrust == pytest.approx(expected, rel=2e-3)


def test_free_fall_without_drag_is_g() -> None:
    p = MulticopterPhysics(load_vehicle("hummingbird"))  # no body drag; stopped rotors have no H-force
    p.reset(position=(0.0, 0.0, -100.0))
    run(p, (0.0,) * 4, 2.0)
    assert p.position[2] == pytest.approx(-100.0 + 0.5 * G * 4.0, abs=1e-9)
    assert p.velocity[2] == pytest.approx(2.0 * G, abs=1e-9)
    assert p.acceleration == pytest.approx((0.0, 0.0, G), abs=1e-9)
    assert p.specific_force == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_sih_free_fall_follows_linear_drag() -> None:
    """SIH_KDV = 1 N/(m/s) on 1 kg: v(t) = g·(1 − e^(−t)) downwards."""
    p = MulticopterPhysics(load_vehicle("sih_quad"))
    p.reset(position=(0.0, 0.0, -100.0))
    run(p, (0.0,) * 4, 2.0)
    assert p.velocity[2] == pytest.approx(G * (1.0 - math.exp(-2.0)), abs=1e-9)
    assert p.position[2] == pytest.approx(-100.0 + G * (2.0 - (1.0 - math.exp(-2.0))), abs=1e-8)


def test_wind_drags_the_vehicle_along() -> None:
    """Drag acts on the air-relative velocity: a hovering SIH quad in a 5 m/s wind reaches wind speed."""
    model = load_vehicle("sih_quad")
    commands = (model.hover_command,) * 4
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -10.0), motor_states=commands)
    run(p, commands, 3.0, wind=(5.0, -2.0, 0.0))
    assert p.velocity[0] == pytest.approx(5.0 * (1.0 - math.exp(-3.0)), abs=1e-6)
    assert p.velocity[1] == pytest.approx(-2.0 * (1.0 - math.exp(-3.0)), abs=1e-6)


@pytest.mark.parametrize("yaw", [0.0, math.pi / 2.0, -2.5])
def test_rotor_drag_opposes_air_velocity(yaw: float) -> None:
    model = load_vehicle("hummingbird")
    commands = (model.hover_command,) * 4
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -10.0), velocity=(3.0, 0.0, 0.0), attitude=from_euler(0.0, 0.0, yaw),
            motor_states=commands)
    p.step(DT, commands)
    # H-force: −k_D·Σω_i·v = −8.06428e-5·4·453.1·3 N on 0.716 kg, whatever the heading.
    expected = -8.06428e-5 * 4 * model.hover_command * 838.0 * 3.0 / model.mass
    assert p.acceleration[0] == pytest.approx(expected, rel=1e-2)
    assert abs(p.acceleration[1]) < 1e-3 * abs(expected)
    # The H-force acts at the hubs 1 cm above the CoG: it tilts the vehicle back against the motion.
    east_axis_rate = p.angular_velocity[0] * math.sin(yaw) + p.angular_velocity[1] * math.cos(yaw)
    assert east_axis_rate > 0.0
    # Flying with the wind at the same speed: no air velocity, no H-force.
    p.reset(position=(0.0, 0.0, -10.0), velocity=(3.0, 0.0, 0.0), motor_states=commands)
    p.step(DT, commands, (3.0, 0.0, 0.0))
    assert p.acceleration[0] == pytest.approx(0.0, abs=1e-9)


def test_rotor_drag_damps_yaw_rate() -> None:
    model = load_vehicle("firefly")
    commands = (model.hover_command,) * 6
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -10.0), angular_velocity=(0.0, 0.0, 1.0), motor_states=commands)
    run(p, commands, 0.5)
    assert 0.0 < p.angular_velocity[2] < 1.0


# Sign conventions -------------------------------------------------------------------------------------------------


def angular_acceleration_for(model: VehicleModel, commands: tuple[float, ...]) -> tuple[float, float, float]:
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -10.0), motor_states=commands)
    p.step(1e-4, commands)
    return p.angular_acceleration


def test_px4_quad_x_mixer_rows_give_positive_accelerations() -> None:
    """PX4's quad X allocation rows (ControlAllocationPseudoInverse.cpp, PX4 motor order) produce positive roll,
    pitch and yaw accelerations."""
    model = load_vehicle("sih_quad")
    hover = model.hover_command
    # Expected from SIH's moment formulas: 0.2 m · 5 N · 4 · 0.05·0.7071 / 0.025 kg·m², and 0.1 N·m · 4 · 0.05 / 0.03.
    rows = {
        0: ((-0.7071, 0.7071, 0.7071, -0.7071), 0.2 * 5.0 * 4 * 0.05 * 0.7071 / 0.025),  # roll
        1: ((0.7071, -0.7071, 0.7071, -0.7071), 0.2 * 5.0 * 4 * 0.05 * 0.7071 / 0.025),  # pitch
        2: ((1.0, 1.0, -1.0, -1.0), 0.1 * 4 * 0.05 / 0.03),  # yaw
    }
    for axis, (row, expected) in rows.items():
        commands = tuple(hover + 0.05 * r for r in row)
        acc = angular_acceleration_for(model, commands)
        assert acc[axis] == pytest.approx(expected, rel=1e-3)
        for other in range(3):
            if other != axis:
                assert abs(acc[other]) < 1e-9


def test_ccw_rotors_yaw_the_body_clockwise_seen_from_above() -> None:
    for name in ALL_VEHICLES:
        model = load_vehicle(name)
        hover = model.hover_command
        commands = tuple(hover + (0.05 if r.spin > 0 else -0.05) for r in model.rotors)
        assert angular_acceleration_for(model, commands)[2] > 0.0, name


@pytest.mark.parametrize("name", ALL_VEHICLES)
def test_physics_moments_agree_with_the_airframe_effectiveness(name: str) -> None:
    """Raising one rotor's normalised thrust by δ gives I·ω̇ equal to δ times its CA_* effectiveness column."""
    model = load_vehicle(name)
    af = model.airframe
    fac = af["THR_MDL_FAC"]
    base_thrust = af["MPC_THR_HOVER"]
    base = (command_for_thrust(base_thrust, fac),) * model.rotor_count
    base_acc = angular_acceleration_for(model, base)
    delta = 0.05
    inertia = model.inertia
    for i, column in enumerate(effectiveness(model)):
        commands = tuple(command_for_thrust(base_thrust + delta, fac) if j == i else c for j, c in enumerate(base))
        acc = angular_acceleration_for(model, commands)
        moment = tuple(inertia[k] * (acc[k] - base_acc[k]) for k in range(3))
        expected = tuple(delta * column[k] for k in range(3))
        assert moment == pytest.approx(expected, abs=2e-3 * max(abs(e) for e in expected)), (name, i)


# Motors -----------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["sih_quad", "hummingbird"])
def test_motor_lag_time_constants(name: str) -> None:
    model = load_vehicle(name)
    p = MulticopterPhysics(model)
    p.reset()
    tau_up, tau_down = model.motor.time_constant_up, model.motor.time_constant_down
    run(p, (1.0,) * 4, tau_up, dt=tau_up / 10.0)
    assert p.motor_states[0] == pytest.approx(1.0 - math.exp(-1.0), abs=1e-9)
    p.reset(motor_states=(1.0,) * 4)
    run(p, (0.0,) * 4, tau_down, dt=tau_down / 10.0)
    assert p.motor_states[0] == pytest.approx(math.exp(-1.0), abs=1e-9)
    # Exact discretisation: the result does not depend on the step size.
    p.reset()
    run(p, (1.0,) * 4, tau_up, dt=tau_up / 2.0)
    assert p.motor_states[0] == pytest.approx(1.0 - math.exp(-1.0), abs=1e-9)


def test_motor_commands_are_clamped_and_nan_stops() -> None:
    p = MulticopterPhysics(load_vehicle("sih_quad"))
    p.reset(motor_states=(0.5,) * 4)
    run(p, (math.nan, -1.0, 2.0, 0.5), 1.0)
    assert p.motor_states == pytest.approx((0.0, 0.0, 1.0, 0.5), abs=1e-6)
    with pytest.raises(ValueError, match="expected 4 motor commands"):
        p.step(DT, (0.5,) * 3)


# Integration accuracy and limits ----------------------------------------------------------------------------------


def final_state(model: VehicleModel, dt: float) -> tuple[float, ...]:
    commands = tuple(model.hover_command + d for d in (0.06, -0.02, 0.03, -0.04, 0.02, 0.0)[: model.rotor_count])
    p = MulticopterPhysics(model)
    p.reset(position=(0.0, 0.0, -50.0), velocity=(1.0, -2.0, 0.5), angular_velocity=(1.0, -0.5, 0.8),
            motor_states=commands)
    run(p, commands, 1.0, wind=(2.0, 1.0, 0.0), dt=dt)
    return (*p.position, *p.velocity, *p.attitude, *p.angular_velocity)


@pytest.mark.parametrize("name", ["sih_quad", "firefly"])
def test_rk4_converges_at_fourth_order(name: str) -> None:
    model = load_vehicle(name)
    reference = final_state(model, 0.000125)
    err_coarse = max(abs(a - b) for a, b in zip(final_state(model, 0.004), reference, strict=True))
    err_fine = max(abs(a - b) for a, b in zip(final_state(model, 0.002), reference, strict=True))
    assert err_fine < 1e-7
    assert err_coarse / err_fine > 12.0  # 2⁴ = 16 for a fourth-order method


def test_body_rates_are_clamped_at_6pi() -> None:
    model = load_vehicle("sih_quad")
    p = MulticopterPhysics(model)
    commands = (0.0, 1.0, 1.0, 0.0)  # full roll
    p.reset(position=(0.0, 0.0, -1000.0), motor_states=commands)
    run(p, commands, 2.0)
    assert max(abs(w) for w in p.angular_velocity) <= 6.0 * math.pi + 1e-12
    assert p.angular_velocity[0] == pytest.approx(6.0 * math.pi)


# Ground contact ---------------------------------------------------------------------------------------------------


def test_rests_on_the_ground_without_sinking_or_sliding() -> None:
    model = load_vehicle("sih_quad")
    p = MulticopterPhysics(model)
    p.reset(position=(3.0, -2.0, 0.0), attitude=from_euler(0.0, 0.0, 1.0))
    assert p.on_ground
    commands = (0.4, 0.45, 0.35, 0.3)  # below hover, with roll/pitch/yaw moments
    for _ in range(5000):
        p.step(DT, commands, (4.0, 3.0, 0.0))
        assert p.position == (3.0, -2.0, 0.0)
        assert p.on_ground
    assert p.velocity == (0.0, 0.0, 0.0)
    assert to_euler(p.attitude) == pytest.approx((0.0, 0.0, 1.0), abs=1e-12)
    assert p.specific_force == pytest.approx((0.0, 0.0, -G), abs=1e-12)


def test_takes_off_when_thrust_exceeds_weight() -> None:
    model = load_vehicle("hummingbird")
    p = MulticopterPhysics(model)
    p.reset()
    hover = model.hover_command
    run(p, (hover - 0.01,) * 4, 1.0)
    assert p.on_ground and p.position[2] == 0.0
    run(p, (hover + 0.05,) * 4, 1.0)
    assert not p.on_ground
    assert p.position[2] < -0.3
    assert p.velocity[2] < 0.0


@pytest.mark.parametrize("name", ALL_VEHICLES)
def test_touchdown_stops_without_penetration(name: str) -> None:
    model = load_vehicle(name)
    p = MulticopterPhysics(model)
    commands = (model.hover_command * 0.9,) * model.rotor_count
    p.reset(position=(0.0, 0.0, -2.0), velocity=(1.0, 0.0, 3.0), attitude=from_euler(0.05, -0.03, 0.2),
            motor_states=commands)
    touched = False
    for _ in range(3000):
        p.step(DT, commands)
        assert p.position[2] <= 0.0
        if p.on_ground:
            if not touched:
                touched = True
                touchdown = p.position
            assert p.position == touchdown
            assert p.velocity == (0.0, 0.0, 0.0)
    assert touched and p.on_ground
    assert p.angular_velocity == (0.0, 0.0, 0.0)
    roll, pitch, _ = to_euler(p.attitude)
    assert (roll, pitch) == (0.0, 0.0)


@pytest.mark.parametrize("roll_deg", [5.0, 30.0])
def test_a_tilted_touchdown_tips_onto_the_legs_with_rates_the_gyro_sees(roll_deg: float) -> None:
    model = load_vehicle("sih_quad")
    p = MulticopterPhysics(model)
    start = from_euler(math.radians(roll_deg), 0.0, 0.7)
    p.reset(position=(0.0, 0.0, -0.01), velocity=(0.0, 0.0, 1.0), attitude=start)
    tipping = 0
    for _ in range(200):
        before = p.attitude
        p.step(DT, (0.0,) * model.rotor_count)
        if not p.on_ground:
            continue
        w = p.angular_velocity
        assert math.sqrt(sum(c * c for c in w)) <= GROUND_TIP_RATE + 1e-9
        tipping += w != (0.0, 0.0, 0.0)
        # The step's rotation is the body rates over dt: what a gyro measures explains the attitude.
        assert angle_between(mul(before, from_rotation_vector(tuple(c * DT for c in w))), p.attitude) < 1e-6
    roll, pitch, yaw = to_euler(p.attitude)
    assert (roll, pitch) == (0.0, 0.0) and yaw == pytest.approx(0.7, abs=1e-3)
    assert p.angular_velocity == (0.0, 0.0, 0.0)
    assert tipping >= math.ceil(math.radians(roll_deg) / (GROUND_TIP_RATE * DT))


def test_reset_below_ground_puts_the_vehicle_on_the_ground() -> None:
    p = MulticopterPhysics(load_vehicle("sih_quad"))
    p.reset(position=(1.0, 2.0, 0.5), velocity=(1.0, 1.0, 1.0), attitude=from_euler(0.3, 0.2, -0.5))
    assert p.on_ground
    assert p.position == (1.0, 2.0, 0.0)
    assert p.velocity == (0.0, 0.0, 0.0)
    assert to_euler(p.attitude) == pytest.approx((0.0, 0.0, -0.5))
