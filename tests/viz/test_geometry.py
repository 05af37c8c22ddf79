"""Vehicle drawing geometry: rotors from CA_ROTOR* parameters, rotor discs."""

import math

import pytest

from stack.viz.geometry import GENERIC_QUAD_X, disc_radius, rotor_disc, rotors_from_params


def test_rotors_from_control_allocation_parameters():
    params = {"CA_ROTOR_COUNT": 2, "CA_ROTOR0_PX": 0.1, "CA_ROTOR0_PY": 0.2, "CA_ROTOR0_PZ": 0.0}
    params |= {"CA_ROTOR1_PX": -0.1, "CA_ROTOR1_PY": -0.2, "CA_ROTOR1_PZ": 0.05, "CA_ROTOR2_PX": 9.0}
    assert rotors_from_params(params) == ((0.1, 0.2, 0.0), (-0.1, -0.2, 0.05))


@pytest.mark.parametrize(
    "params",
    [
        {},
        {"CA_ROTOR_COUNT": 0},
        {"CA_ROTOR_COUNT": 1, "CA_ROTOR0_PX": 0.1},
        {"CA_ROTOR_COUNT": "four"},
    ],
)
def test_no_rotors_when_the_parameters_do_not_describe_any(params):
    assert rotors_from_params(params) is None


def test_disc_radius_keeps_neighbouring_discs_apart():
    # Quad X with 0.2 m offsets: neighbours are 0.4 m apart, so discs of 0.16 m leave a gap.
    assert disc_radius(GENERIC_QUAD_X) == pytest.approx(0.16)
    assert disc_radius([(0.0, 0.0, 0.0)]) == pytest.approx(0.2)


def test_rotor_disc_is_a_closed_circle_around_the_hub():
    points = rotor_disc((1.0, -1.0, 0.1), 0.5, segments=8)
    assert len(points) == 9
    assert points[0] == pytest.approx(points[-1])
    for x, y, z in points:
        assert math.hypot(x - 1.0, y + 1.0) == pytest.approx(0.5)
        assert z == 0.1
