"""Vehicle files: loading, the figures they carry, airframe consistency and loader errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from stack.airframe.model import VEHICLES_DIR, available_vehicles, load_vehicle

ALL_VEHICLES = ["sih_quad", "hummingbird", "pelican", "firefly"]  # the multicopters


def test_all_shipped_vehicles_load() -> None:
    assert set(available_vehicles()) == {*ALL_VEHICLES, "sih_plane", "jsbsim_c172"}
    assert load_vehicle("sih_plane").name == "sih_plane"  # tests/sim/test_fixedwing_physics.py has the rest
    assert load_vehicle("jsbsim_c172").aircraft == "c172p"  # tests/sim/test_jsbsim_plant.py has the rest
    for name in ALL_VEHICLES:
        model = load_vehicle(name)
        assert model.name == name
        assert model.airframe["CA_ROTOR_COUNT"] == model.rotor_count


def test_sih_quad_figures_match_sih_params() -> None:
    m = load_vehicle("sih_quad")
    assert m.mass == 1.0
    assert m.inertia == (0.025, 0.025, 0.030)
    assert m.motor.thrust_model == "linear"
    assert m.motor.max_thrust == 5.0
    assert m.motor.moment_ratio == pytest.approx(0.1 / 5.0)
    assert (m.motor.time_constant_up, m.motor.time_constant_down) == (0.05, 0.05)
    assert (m.drag.linear, m.drag.quadratic, m.drag.angular) == (1.0, 0.0, 0.025)
    # PX4 quad X order: 1 FR CCW, 2 RL CCW, 3 FL CW, 4 RR CW.
    assert [r.position for r in m.rotors] == [(0.2, 0.2, 0.0), (-0.2, -0.2, 0.0), (0.2, -0.2, 0.0), (-0.2, 0.2, 0.0)]
    assert [r.spin for r in m.rotors] == [1, 1, -1, -1]
    assert m.hover_command == pytest.approx(9.80665 / 20.0)
    assert m.airframe["THR_MDL_FAC"] == 0.0


def test_rotors_vehicles_hover_figures() -> None:
    hb = load_vehicle("hummingbird")
    # Derived in the reference: hover ω ≈ 453 rad/s, max thrust ≈ 24 N in total.
    assert hb.hover_command * hb.motor.max_rotor_speed == pytest.approx(453.1, abs=0.5)
    assert hb.rotor_count * hb.motor.max_thrust == pytest.approx(24.0, abs=0.05)
    assert hb.airframe["THR_MDL_FAC"] == 1.0
    # MPC_THR_HOVER is a normalised thrust; the motor command is its square root for THR_MDL_FAC = 1.
    assert hb.hover_command == pytest.approx(math.sqrt(hb.airframe["MPC_THR_HOVER"]), abs=1e-3)


def test_rotors_geometry_converted_to_frd() -> None:
    hb = load_vehicle("hummingbird")
    # RotorS '+': rotor 0 front CW, 1 left CCW, 2 back CW, 3 right CCW; rotor plane 1 cm above the CoG.
    assert [r.position for r in hb.rotors] == [
        (0.17, 0.0, -0.01), (0.0, -0.17, -0.01), (-0.17, 0.0, -0.01), (0.0, 0.17, -0.01)
    ]
    assert [r.spin for r in hb.rotors] == [-1, 1, -1, 1]
    ff = load_vehicle("firefly")
    assert ff.rotor_count == 6
    for rotor, angle_deg, spin in zip(ff.rotors, (30, 90, 150, -150, -90, -30), (1, -1, 1, -1, 1, -1), strict=True):
        a = math.radians(angle_deg)
        assert rotor.position == pytest.approx((0.215 * math.cos(a), -0.215 * math.sin(a), -0.037), abs=1e-6)
        assert rotor.spin == spin


def test_airframe_table_matches_geometry() -> None:
    for name in ALL_VEHICLES:
        m = load_vehicle(name)
        af = m.airframe
        for i, rotor in enumerate(m.rotors):
            position = (af[f"CA_ROTOR{i}_PX"], af[f"CA_ROTOR{i}_PY"], af[f"CA_ROTOR{i}_PZ"])
            assert position == pytest.approx(rotor.position)
            assert math.copysign(1.0, af[f"CA_ROTOR{i}_KM"]) == rotor.spin
            assert af[f"CA_ROTOR{i}_CT"] == pytest.approx(m.motor.max_thrust, rel=1e-3)
        assert af["MPC_THR_HOVER"] == pytest.approx(m.hover_thrust_fraction, abs=1e-4)


def test_unknown_name_lists_the_available_vehicles() -> None:
    with pytest.raises(ValueError, match=r"unknown vehicle 'nope'.*sih_quad"):
        load_vehicle("nope")


def _broken(tmp_path: Path, source: str, old: str, new: str, name: str = "hummingbird") -> Path:
    text = (VEHICLES_DIR / f"{source}.toml").read_text()
    assert old in text
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("position = [-0.17, 0.0, -0.01]", "position = [-0.17, 0.0]", "rotor[2].position: expected 3 numbers"),
        ('spin = "ccw"', 'spin = "left"', 'rotor[1].spin: expected "ccw" or "cw"'),
        ("mass = 0.716", "mass = -1.0", "mass: must be > 0"),
        ("mass = 0.716", "mass = 3.0", "mass: the rotors cannot lift"),
        ("mass = 0.716", "mass = 0.7", "airframe.MPC_THR_HOVER: is 0.2924, the model hovers at"),
        ('thrust_model = "quadratic"', 'thrust_model = "cubic"', "motor.thrust_model: expected one of"),
        ("time_constant_up = 0.0125", "time_constant_up = 0.0", "motor.time_constant_up: must be > 0"),
        ("time_constant_up = 0.0125", "", "motor.time_constant_up: missing"),
        ("CA_ROTOR0_KM = -0.016", "CA_ROTOR0_KM = 0.016", "airframe.CA_ROTOR0_KM: is 0.016, expected -0.016"),
        ("CA_ROTOR1_KM = 0.016", "CA_ROTOR1_KM = -0.016", "airframe.CA_ROTOR1_KM: is -0.016, expected 0.016"),
        ("CA_ROTOR2_PX = -0.17", "CA_ROTOR2_PX = 0.17", "airframe.CA_ROTOR2_PX: is 0.17"),
        ("CA_ROTOR_COUNT = 4", "CA_ROTOR_COUNT = 6", "airframe.CA_ROTOR_COUNT: is 6"),
        ("THR_MDL_FAC = 1.0", "THR_MDL_FAC = 0.0", "airframe.THR_MDL_FAC: is 0.0"),
        ("THR_MDL_FAC = 1.0", "THR_MDL_FAC = 1.0\nCA_ROTOR7_PX = 0.0", "airframe.CA_ROTOR7_PX: rotor index"),
        ("THR_MDL_FAC = 1.0", "THR_MDL_FAC = 1.0\nthr_mdl_fac = 1.0", "airframe.thr_mdl_fac: expected an"),
        ("MPC_THR_HOVER = 0.2924", "", "airframe.MPC_THR_HOVER: missing"),
        ("[drag]", "[drag]\nsideways = 1.0", "drag.sideways: unknown key"),
        ("max_rotor_speed = 838.0", 'max_rotor_speed = "fast"', "motor.max_rotor_speed: expected a finite"),
        ("inertia = [0.007, 0.007, 0.012]", "inertia = [0.007, 0.0, 0.012]", "inertia: every diagonal"),
        ('name = "hummingbird"', 'name = "hummingbird"\ncolour = "red"', "colour: unknown key"),
    ],
)
def test_loader_errors_name_file_key_and_problem(tmp_path: Path, old: str, new: str, message: str) -> None:
    path = _broken(tmp_path, "hummingbird", old, new)
    with pytest.raises(ValueError) as info:
        load_vehicle(path)
    assert str(info.value).startswith(f"hummingbird.toml: {message}"), str(info.value)


def test_linear_motor_rejects_rotor_drag(tmp_path: Path) -> None:
    path = _broken(tmp_path, "sih_quad", "rotor_drag_coefficient = 0.0", "rotor_drag_coefficient = 1e-4", "sih")
    with pytest.raises(ValueError, match=r"^sih\.toml: motor\.rotor_drag_coefficient: needs"):
        load_vehicle(path)


def test_invalid_toml_is_a_value_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("mass = = 1\n")
    with pytest.raises(ValueError, match=r"^bad\.toml: invalid TOML"):
        load_vehicle(path)


def test_model_is_immutable() -> None:
    m = load_vehicle("sih_quad")
    with pytest.raises(AttributeError):
        m.mass = 2.0  # type: ignore[misc]
    with pytest.raises(TypeError):
        m.airframe["MPC_THR_HOVER"] = 0.3  # type: ignore[index]
