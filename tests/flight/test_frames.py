"""The autonomous scenarios judge positions about home: horizontally by where each truly is (the truth's latitude
and longitude in the estimator's frame), vertically against the heights at arming."""

from types import SimpleNamespace

import pytest

from stack.mathlib.geo import MapProjection
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.registry import ORB_ID
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import HomePosition
from stack.scenario.autonomy import Frames
from stack.scenario.script import Series

SIM_ORIGIN = (47.397742, 8.545594)  # where the simulator's NED frame starts
REF = (47.39775, 8.5456)  # the estimator's reference point, about a metre away


def truth(north: float, east: float, down: float) -> SimGroundtruth:
    lat, lon = MapProjection(*SIM_ORIGIN).reproject(north, east)
    return SimGroundtruth(position=(north, east, down), lat=lat, lon=lon)


def context(home_error: tuple[float, float], xy_global: bool = True) -> SimpleNamespace:
    """Armed at t=1 on the simulator's origin; home is where the estimate put the vehicle then, ``home_error`` off
    in the estimator's frame (north, east), with the ground 0.2 m below the estimate's z origin."""
    at_arming = truth(0.0, 0.0, 0.0)
    north, east = MapProjection(*REF).project(at_arming.lat, at_arming.lon)
    home = HomePosition(x=north + home_error[0], y=east + home_error[1], z=0.2)
    lpos = VehicleLocalPosition(xy_global=xy_global, ref_lat=REF[0], ref_lon=REF[1])
    series = {ORB_ID.sim_groundtruth: Series([0.0, 1.0], [truth(0.0, 0.0, 0.0), at_arming])}
    return SimpleNamespace(
        latest={ORB_ID.home_position: home, ORB_ID.vehicle_local_position: lpos}, series=series, state={"armed_at": 1.0}
    )


def test_a_setpoint_is_judged_against_the_place_it_names_not_against_homes_estimate():
    ctx = context(home_error=(0.3, -0.2))
    frames = Frames(ctx)
    # The vehicle truly 5 m north of where it armed, 5 m up.
    place = frames.truth_about_home(truth(5.0, 0.0, -5.0).position)
    # The same place in the estimator's frame, about home: home's own error shows, as it would for a setpoint.
    north, east = MapProjection(*REF).project(*MapProjection(*SIM_ORIGIN).reproject(5.0, 0.0))
    home = ctx.latest[ORB_ID.home_position]
    assert place == pytest.approx((north - home.x, east - home.y, -5.0), abs=1e-6)
    assert frames.place_about_home(*MapProjection(*SIM_ORIGIN).reproject(5.0, 0.0), 0.0, 0.0) == pytest.approx(
        place[:2], abs=1e-6
    )


def test_without_a_reference_point_positions_are_about_the_vehicle_at_arming():
    frames = Frames(context(home_error=(0.3, -0.2), xy_global=False))
    assert frames.truth_about_home((5.0, 0.0, -5.0)) == (5.0, 0.0, -5.0)
    assert frames.place_about_home(0.0, 0.0, 4.0, 3.0) == (4.0, 3.0)
