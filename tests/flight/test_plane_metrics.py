"""How a fixed-wing flight is judged (stack.scenario.plane_metrics), worked by hand."""

from __future__ import annotations

import math

import pytest

from stack.scenario.plane_metrics import (
    Sample,
    leg_errors,
    loiter_radius_errors,
    summary,
    touchdown_sink,
    turn_overshoot,
)


def at(north: float, east: float, altitude: float = 40.0, airspeed: float = 15.0, sp: float = 15.0) -> Sample:
    return Sample(0.0, (north, east, -altitude), airspeed, sp)


def test_a_leg_is_judged_on_its_second_half_only() -> None:
    flown = [at(100.0, 5.0), at(250.0, 2.0, 41.0, 16.0), at(400.0, -1.0, 39.5, 14.0), at(450.0, 9.0)]
    errors = leg_errors(flown, (0.0, 0.0), (400.0, 0.0), 40.0)
    assert errors.xtrack == [2.0, -1.0]  # right of a northbound line is east: positive
    assert errors.altitude == [1.0, -0.5]
    assert errors.airspeed == [1.0, -1.0]
    assert summary(errors.xtrack) == pytest.approx((math.sqrt(2.5), 2.0))
    assert summary([]) == (pytest.approx(math.nan, nan_ok=True), pytest.approx(math.nan, nan_ok=True))


def test_the_overshoot_of_a_turn_is_measured_on_its_outside() -> None:
    # North, then a right turn to the east at (400, 0): the outside is north of the new leg.
    flown = [at(403.0, 10.0), at(398.0, 50.0), at(405.0, 350.0)]
    assert turn_overshoot(flown, (0.0, 0.0), (400.0, 0.0), (400.0, 400.0)) == pytest.approx(3.0)
    inside = [at(395.0, 20.0)]
    assert turn_overshoot(inside, (0.0, 0.0), (400.0, 0.0), (400.0, 400.0)) == 0.0


def test_the_loiter_counts_from_the_first_time_on_the_circle() -> None:
    flown = [at(0.0, 100.0), at(0.0, 62.0), at(0.0, 20.0), at(-58.0, 0.0)]
    assert loiter_radius_errors(flown, (0.0, 0.0), 60.0) == pytest.approx([2.0, -40.0, -2.0])


def test_the_touchdown_is_the_hardest_first_contact_after_flying() -> None:
    on_ground = [True, True, False, False, True, False, True, True]
    down_speed = [0.0, -0.5, -2.0, 0.9, 0.1, 1.4, 0.2, 0.0]  # the takeoff, a touchdown at 0.9, a bounce at 1.4
    assert touchdown_sink(on_ground, down_speed) == 1.4
    assert math.isnan(touchdown_sink([True, False, False], [0.0, -1.0, -1.0]))
