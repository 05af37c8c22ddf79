"""Where a fixed-wing landing counts as on the runway (stack.fw.runway), worked by hand."""

import math

import pytest

from stack.fw.runway import on_runway


def test_the_runway_runs_from_its_threshold_behind_its_start_along_the_takeoff_heading() -> None:
    east = 0.5 * math.pi
    home = (0.0, 0.0)
    assert on_runway((1.0, 300.0), home, east) == pytest.approx((True, 300.0, -1.0))  # north: left of it
    assert not on_runway((10.5, 300.0), home, east)[0]  # off to the left of an eastbound runway
    assert on_runway((0.0, -49.0), home, east)[0] and not on_runway((0.0, -51.0), home, east)[0]
    assert on_runway((0.0, 599.0), home, east)[0] and not on_runway((0.0, 601.0), home, east)[0]
    assert on_runway((105.0, 205.0), (100.0, 200.0), 0.25 * math.pi) == pytest.approx((True, 50**0.5, 0.0))
