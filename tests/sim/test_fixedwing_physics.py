"""The SIH airplane plant: its vehicle file, control signs, trim, stability and the landing gear."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from stack.airframe.model import VEHICLES_DIR, FixedwingModel, load_vehicle
from stack.mathlib.quaternion import from_euler, to_euler
from stack.sim.fixedwing_physics import FixedwingPhysics, level_trim, rest_pose

HOME_ALT = 489.4  # SIH_LOC_H0
DT = 0.002  # 500 Hz
PLANE = load_vehicle("sih_plane")
assert isinstance(PLANE, FixedwingModel)


def run(p: FixedwingPhysics, seconds: float, commands: tuple[float, ...], wind=(0.0, 0.0, 0.0), each=None) -> None:
    for i in range(round(seconds / DT)):
        p.step(DT, commands, wind)
        if each is not None:
            each(p, (i + 1) * DT)


def airborne_at_trim(speed: float, altitude: float = 100.0) -> tuple[FixedwingPhysics, tuple[float, ...]]:
    trim = level_trim(PLANE, speed, HOME_ALT + altitude)
    p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
    p.reset((0.0, 0.0, -altitude), (speed, 0.0, 0.0), from_euler(0.0, trim.pitch, 0.0), motor_states=[trim.throttle])
    return p, (trim.throttle, 0.0, trim.elevator, 0.0)


# ---------------------------------------------------------------------------------------------- vehicle file


def test_the_sih_airplane_figures() -> None:
    m = PLANE
    assert (m.mass, m.inertia, m.inertia_xz) == (0.3, (0.00402, 0.0144, 0.0177), 0.00046)
    assert m.input_count == 4 and m.rotor_count == 1
    assert m.max_deflection == pytest.approx(math.pi / 12)
    assert (m.drag.linear, m.drag.angular) == (0.2, 0.025)
    assert m.thruster.time_constant == 0.05 and m.thruster.prop_radius == 0.1
    assert m.thruster.max_thrust == pytest.approx(12.84, abs=0.01)  # APC 8x6" at 13000 RPM, static
    names = [s.name for s in m.segments]
    assert names == ["left wing", "right wing", "tailplane", "fin", "fuselage"]
    left, right, tail, fin, fuselage = m.segments
    assert (left.span, left.chord, left.position) == (0.43, 0.21, (0.0, -0.215, 0.0))
    assert left.alpha_0 == pytest.approx(-4 * math.pi / 180) and left.dihedral == pytest.approx(3 * math.pi / 180)
    assert right.dihedral == -left.dihedral and left.flap_chord == pytest.approx(0.21 / 3)
    assert (left.control, left.direction, right.control, right.direction) == ("aileron", 1, "aileron", -1)
    assert (tail.position, tail.flap_chord, tail.control, tail.direction) == ((-0.4, 0.0, 0.0), 0.05, "elevator", -1)
    assert (fin.position, fin.flap_chord, fin.control, fin.direction) == ((-0.45, 0.0, -0.1), 0.12, "rudder", 1)
    assert tail.slipstream and fin.slipstream and not left.slipstream and not fuselage.slipstream
    assert (fuselage.span, fuselage.chord, fuselage.control) == (0.2, 0.8, None)
    assert dict(m.airframe) == {"CA_AIRFRAME": 1, "CA_ROTOR_COUNT": 1}


def write_variant(tmp_path: Path, old: str, new: str) -> Path:
    text = (VEHICLES_DIR / "sih_plane.toml").read_text()
    assert old in text
    path = tmp_path / "plane.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("CA_AIRFRAME = 1", "CA_AIRFRAME = 0", r"airframe.CA_AIRFRAME: is 0, the fixed-wing model needs 1"),
        ("CA_ROTOR_COUNT = 1", "CA_ROTOR_COUNT = 4", r"airframe.CA_ROTOR_COUNT: is 4"),
        ('control = "rudder"\ndirection = 1\n', "", r"segment: no segment is moved by the rudder"),
        ('control = "rudder"', 'control = "flaps"', r"segment\[3\].control: expected one of aileron"),
        ("direction = -1", "direction = 2", r"segment\[1\].direction: expected 1 or -1"),
        ("diameter = 0.2032", "max_thrust = 6.0\ndiameter = 0.2032", r"thruster.max_thrust: either max_thrust"),
        ("inertia_xz = 0.00046", "inertia_xz = 0.01", r"inertia_xz: makes the inertia tensor singular"),
        ("slipstream = true", "slipstream = 1", r"segment\[2\].slipstream: expected true or false"),
        ('wheel = false\n\n[[contact]]\nname = "spinner"',
         'wheel = false\nbrake = true\n\n[[contact]]\nname = "spinner"', r"contact\[3\].brake: only for a wheel"),
    ],
)
def test_loader_errors_name_the_file_and_key(tmp_path: Path, old: str, new: str, message: str) -> None:
    with pytest.raises(ValueError, match=r"plane.toml: " + message):
        load_vehicle(write_variant(tmp_path, old, new))


def test_a_constant_thrust_plane_loads(tmp_path: Path) -> None:
    text = (VEHICLES_DIR / "sih_plane.toml").read_text()
    start = text.index("diameter = 0.2032")
    end = text.index("time_constant = 0.05")
    path = tmp_path / "plane6.toml"
    path.write_text(text[:start] + "max_thrust = 6.0\n" + text[end:])
    m = load_vehicle(path)
    assert isinstance(m, FixedwingModel) and m.thruster.propeller is None and m.thruster.max_thrust == 6.0


def test_an_unknown_vehicle_type_is_refused(tmp_path: Path) -> None:
    path = write_variant(tmp_path, 'type = "fixedwing"', 'type = "blimp"')
    with pytest.raises(ValueError, match=r"plane.toml: type: 'blimp' is not a vehicle type"):
        load_vehicle(path)


# ---------------------------------------------------------------------------------------------- in the air


@pytest.mark.parametrize(("index", "axis"), [(1, 0), (2, 1), (3, 2)])
def test_a_positive_command_gives_a_positive_torque(index: int, axis: int) -> None:
    """+aileron rolls right, +elevator pitches nose up, +rudder yaws right (the actuator convention)."""
    accelerations = []
    for command in (-0.5, 0.0, 0.5):
        p, trim = airborne_at_trim(15.0)
        commands = list(trim)
        commands[index] += command
        p.step(DT, tuple(commands))
        accelerations.append(p.angular_acceleration[axis])
    assert accelerations[0] < accelerations[1] < accelerations[2]
    assert accelerations[2] > 1.0  # rad/s², a real control authority


def test_level_trim_at_12_15_and_18_m_s() -> None:
    expected = {12.0: (0.472, -0.120, -1.35), 15.0: (0.667, -0.188, -2.31), 18.0: (0.894, -0.230, -2.85)}
    for speed, (throttle, elevator, pitch_deg) in expected.items():
        trim = level_trim(PLANE, speed, HOME_ALT)
        assert trim.throttle == pytest.approx(throttle, abs=0.002)
        assert trim.elevator == pytest.approx(elevator, abs=0.002)
        assert math.degrees(trim.pitch) == pytest.approx(pitch_deg, abs=0.02)
    # Flat out the propeller holds about 19.3 m/s level here (PX4: 19.7 m/s "in near level flight").
    with pytest.raises(ValueError, match="no level trim at 20"):
        level_trim(PLANE, 20.0, HOME_ALT)


def test_flying_the_trim_holds_speed_height_and_attitude() -> None:
    p, commands = airborne_at_trim(15.0, altitude=100.0)
    q0 = p.attitude
    run(p, 5.0, commands)
    assert p.velocity == pytest.approx((15.0, 0.0, 0.0), abs=0.02)
    assert p.position[2] == pytest.approx(-100.0, abs=0.05)
    assert p.position[0] == pytest.approx(75.0, abs=0.1)
    assert to_euler(p.attitude) == pytest.approx(to_euler(q0), abs=1e-3)


def test_pitch_disturbance_decays_statically_stable() -> None:
    p, commands = airborne_at_trim(15.0)
    trim_pitch = to_euler(p.attitude)[1]
    p.reset(p.position, p.velocity, p.attitude, (0.0, 1.0, 0.0), p.motor_states)  # a 1 rad/s pitch-up kick
    rates = []
    run(p, 3.0, commands, each=lambda p, t: rates.append((t, abs(p.angular_velocity[1]))))
    assert max(r for t, r in rates if t >= 0.5) < 0.1
    assert max(r for t, r in rates if t >= 2.0) < 0.02
    # The nose comes back: the angle of attack returns to the trim's within a degree (the phugoid is slow).
    vx, _, vz = p.velocity
    alpha = to_euler(p.attitude)[1] + math.atan2(vz, vx)
    assert math.degrees(alpha) == pytest.approx(math.degrees(trim_pitch), abs=1.0)


def test_stall_speed_the_wing_cannot_carry_the_weight_below_it() -> None:
    # The wing's C_L,max is 1.489 (at 21° on the plate, 17° of flow); 1 g at 489 m AMSL (ρ = 1.1686):
    # V_s = √(2mg / (ρ·S·C_L,max)) = √(5.884 / (1.1686·0.1806·1.489)) = 4.33 m/s.
    level_trim(PLANE, 5.0, HOME_ALT)
    with pytest.raises(ValueError):
        level_trim(PLANE, 4.0, HOME_ALT)


def test_non_finite_and_out_of_range_commands_are_safe() -> None:
    p, commands = airborne_at_trim(15.0)
    p.step(DT, (math.nan, math.inf, -math.inf, 7.0))
    assert all(math.isfinite(c) for c in (*p.position, *p.velocity, *p.angular_velocity))
    assert p.motor_states[0] < commands[0]  # NaN throttle counts as 0: the motor winds down
    with pytest.raises(ValueError, match="expected 4 commands"):
        p.step(DT, (0.5, 0.0))


# ---------------------------------------------------------------------------------------------- on the ground


def test_rest_pose_is_the_gear_static_equilibrium() -> None:
    height, roll, pitch = rest_pose(PLANE)
    # Nose 200 N/m carries 20 %, each main 400 N/m 40 % of 2.942 N: all three sink by 2.942 mm.
    assert height == pytest.approx(0.12 - 0.3 * 9.80665 / 1000.0, abs=1e-9)
    assert roll == pytest.approx(0.0, abs=1e-9) and pitch == pytest.approx(0.0, abs=1e-9)


def test_at_rest_with_zero_throttle_it_stays_put() -> None:
    p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
    p.reset((3.0, -2.0, 0.0), attitude=from_euler(0.0, 0.0, 1.0))
    assert p.on_ground and p.position == (3.0, -2.0, 0.0)
    run(p, 10.0, (0.0, 0.3, -0.4, 0.2))  # surfaces moving, no throttle
    assert p.position == pytest.approx((3.0, -2.0, 0.0), abs=1e-9)
    assert p.velocity == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert to_euler(p.attitude) == pytest.approx((0.0, 0.0, 1.0), abs=1e-9)
    assert p.on_ground


def test_the_brakes_hold_it_in_a_light_wind_without_creeping() -> None:
    p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
    positions = []
    run(p, 10.0, (0.0, 0.0, 0.0, 0.0), wind=(-3.0, 0.0, 0.0), each=lambda p, t: positions.append(p.position))
    # The tread springs give a few millimetres, then nothing moves.
    assert abs(positions[-1][0]) < 0.01
    assert positions[-1] == pytest.approx(positions[len(positions) // 2], abs=1e-9)


def test_full_throttle_takes_off_within_a_few_metres() -> None:
    for elevator, (distance, speed) in ((0.0, (1.47, 9.0)), (0.2, (0.43, 5.0))):
        p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
        liftoff: list[tuple[float, float]] = []

        def record(p: FixedwingPhysics, t: float, liftoff: list[tuple[float, float]] = liftoff) -> None:
            if not p.on_ground:
                liftoff.append((p.position[0], math.hypot(*p.velocity)))

        run(p, 2.0, (1.0, 0.0, elevator, 0.0), each=record)
        assert liftoff, "it never left the ground"
        assert liftoff[0] == pytest.approx((distance, speed), abs=0.1)
        assert -p.position[2] > 3.0  # climbing away
        assert abs(p.position[1]) < 1e-6


def test_a_one_metre_per_second_touchdown_settles_without_bouncing() -> None:
    p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
    p.reset((0.0, 0.0, -0.05), (10.0, 0.0, 1.0), from_euler(0.0, math.radians(3.0), 0.0))
    heights = []
    run(p, 8.0, (0.0, 0.0, 0.0, 0.0), each=lambda p, t: heights.append((t, -p.position[2], p.on_ground)))
    touchdown = next(i for i, (_, _, ground) in enumerate(heights) if ground)
    deepest = min(range(touchdown, len(heights)), key=lambda i: heights[i][1])
    assert heights[deepest][1] > -0.02  # the gear takes it in under 2 cm
    assert max(h for _, h, _ in heights[deepest:]) < 0.02  # no bounce above 2 cm
    assert all(ground for _, _, ground in heights[deepest:])
    # Braked to a stop on its wheels, level, at the rest height.
    assert p.velocity == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)
    assert p.position[2] == pytest.approx(0.0, abs=1e-4)
    assert to_euler(p.attitude)[:2] == pytest.approx((0.0, 0.0), abs=1e-3)


def test_a_hard_touchdown_does_not_launch_it() -> None:
    p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
    p.reset((0.0, 0.0, -0.02), (0.0, 0.0, 3.0))
    heights = []
    run(p, 2.0, (0.0, 0.0, 0.0, 0.0), each=lambda p, t: heights.append(-p.position[2]))
    lowest = heights.index(min(heights))
    assert min(heights) > -0.05
    assert max(heights[lowest:]) < 0.01


def test_the_nose_wheel_steers_with_the_rudder() -> None:
    for rudder in (0.5, -0.5):
        p = FixedwingPhysics(PLANE, home_altitude=HOME_ALT)
        run(p, 2.0, (0.12, 0.0, -0.3, 0.0))
        run(p, 1.0, (0.12, 0.0, -0.3, rudder))
        assert math.copysign(1.0, p.angular_velocity[2]) == math.copysign(1.0, rudder)
        assert math.copysign(1.0, p.position[1]) == math.copysign(1.0, rudder)
        assert p.on_ground and abs(to_euler(p.attitude)[0]) < math.radians(3.0)  # on its wheels
