"""A parameter definition checks and converts values: from numbers, and from text as typed or read from a file."""

import math

import pytest

from stack.names import suggestion
from stack.params.param import Param, ParamError


def test_values_are_converted_to_the_parameters_type():
    gain = Param("G", 1.0, -2.0, 2.0)
    assert gain.check("-1.5") == -1.5 and gain.check(1) == 1.0 and type(gain.check(1)) is float
    count = Param("N", 4, 1, 16)
    assert count.check("8") == 8 and count.check(8.0) == 8
    flag = Param("F", True)
    assert flag.check("false") is False and flag.check(1) is True and flag.check("0") is False


@pytest.mark.parametrize(
    ("p", "value", "why"),
    [
        (Param("G", 1.0, -2.0, 2.0), "-3", "below the minimum -2"),
        (Param("G", 1.0, -2.0, 2.0), 2.5, "above the maximum 2"),
        (Param("G", 1.0), math.nan, "not a finite number"),
        (Param("G", 1.0), "fast", "expected a number"),
        (Param("G", 1.0), True, "expected a number"),
        (Param("N", 4, 1, 16), 3.5, "expected an integer"),
        (Param("N", 4, 1, 16), "four", "expected an integer"),
        (Param("F", True), 2, "expected a boolean"),
        (Param("E", 0, 0, 2, values={0: "Off", 2: "On"}), 1, r"1 is not one of 0 \(Off\), 2 \(On\)"),
    ],
)
def test_a_bad_value_is_refused_with_the_reason(p, value, why):
    with pytest.raises(ParamError, match=why):
        p.check(value)


def test_only_an_integer_parameter_has_values_or_bits():
    with pytest.raises(TypeError, match="only an int parameter"):
        Param("X", 0.0, values={0: "Off"})


def test_the_closest_name_is_suggested_whatever_the_case():
    assert suggestion("mc_rollrate_p", ["MC_ROLLRATE_P", "MC_PITCHRATE_P"]) == " (did you mean MC_ROLLRATE_P?)"
    assert suggestion("XYZZY", ["MC_ROLLRATE_P"]) == ""
