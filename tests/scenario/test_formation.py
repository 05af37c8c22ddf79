"""The formation law (stack.scenario.formation) and the swarm's judgement from tracks (stack.scenario.swarm_track)."""

from __future__ import annotations

import json
import math

import pytest

from stack.mathlib.geo import MapProjection
from stack.msg.estimation import VehicleLocalPosition
from stack.scenario import formation
from stack.scenario.swarm_track import Tracks, swarm_role

LAT, LON = 47.397742, 8.545594


def position(ref: tuple[float, float], x: float, y: float, z: float, **fields: object) -> VehicleLocalPosition:
    given: dict[str, object] = {"xy_valid": True, "z_valid": True, "xy_global": True, **fields}
    return VehicleLocalPosition(ref_lat=ref[0], ref_lon=ref[1], x=x, y=y, z=z, **given)


def test_a_follower_places_the_leader_by_latitude_and_longitude_and_its_height_about_its_own_home() -> None:
    leader_ref = (LAT, LON)
    own_ref = MapProjection(LAT, LON).reproject(3.0, 5.0)  # the follower's frame starts 3 m north, 5 m east
    leader = position(leader_ref, 10.0, 2.0, -5.0)
    own = position(own_ref, 0.0, 0.0, -4.0)
    sp = formation.formation_setpoint(leader, own, own_home_z=0.4, offset=(0.0, 5.0, 0.0), now_us=0)
    assert sp is not None
    assert sp.position == pytest.approx((7.0, 2.0, -4.6), abs=1e-4)  # two projections: µm apart
    assert sp.velocity == (0.0, 0.0, 0.0)


def test_the_position_heard_is_carried_on_to_now_with_the_leaders_velocity() -> None:
    leader = position((LAT, LON), 0.0, 0.0, -5.0, vx=2.0, vy=-1.0, vz=0.5, timestamp_sample=1_000_000)
    own = position((LAT, LON), 0.0, 0.0, -5.0)
    sp = formation.formation_setpoint(leader, own, 0.0, (0.0, 0.0, 0.0), now_us=1_100_000)
    assert sp is not None
    assert sp.position == pytest.approx((0.2, -0.1, -4.95), abs=1e-6)
    assert sp.velocity == (2.0, -1.0, 0.5)


def test_no_setpoint_without_reference_points_or_a_valid_leader() -> None:
    own = position((LAT, LON), 0.0, 0.0, 0.0)
    no_ref = VehicleLocalPosition(xy_valid=True, z_valid=True)
    assert formation.formation_setpoint(no_ref, own, 0.0, (0.0, 0.0, 0.0), 0) is None
    invalid = position((LAT, LON), 0.0, 0.0, 0.0, xy_valid=False)
    assert formation.formation_setpoint(invalid, own, 0.0, (0.0, 0.0, 0.0), 0) is None


def test_a_leader_is_lost_once_its_newest_position_is_older_than_the_timeout() -> None:
    heard = position((LAT, LON), 0.0, 0.0, 0.0, timestamp_sample=10_000_000)
    timeout_us = round(formation.LEADER_TIMEOUT_S * 1e6)
    assert not formation.leader_lost(heard, 10_000_000 + timeout_us)
    assert formation.leader_lost(heard, 10_000_000 + timeout_us + 1)
    assert formation.leader_lost(None, 0)


def test_slots_line_up_abreast_as_far_apart_as_the_homes() -> None:
    assert formation.slot_offset(1, 5.0) == (0.0, 0.0, 0.0)
    assert formation.slot_offset(3, 5.0) == (0.0, 10.0, 0.0)


def test_the_box_is_flown_side_by_side_from_stop_to_stop_and_ends_where_it_began() -> None:
    start = (1.0, -2.0, -5.0)
    step = 0.01
    previous, _, _ = formation.box_setpoint(start, 0.0)
    corners, t, done = [], 0.0, False
    top_speed = 0.0
    while not done:
        t += step
        pos, vel, done = formation.box_setpoint(start, t)
        speed = math.hypot(vel[0], vel[1])
        top_speed = max(top_speed, speed)
        # The velocity is the path's own: the position moves by it.
        assert math.dist(pos, previous) <= formation.BOX_SPEED_M_S * step + 1e-9
        if speed < 1e-9 and not done:
            corners.append((round(pos[0], 6), round(pos[1], 6)))
        assert pos[2] == start[2]
        previous = pos
    assert pos == start and vel == (0.0, 0.0, 0.0)
    assert top_speed == pytest.approx(formation.BOX_SPEED_M_S)
    side = formation.BOX_SIDE_M
    for corner in [(1.0 + side, -2.0), (1.0 + side, -2.0 + side), (1.0, -2.0 + side)]:
        assert any(math.dist(corner, c) < 1e-3 for c in corners), corner


def track(north: float, east: float, times: range) -> list[list[float]]:
    lat, lon = MapProjection(LAT, LON).reproject(north, east)
    return [[t * 0.1, lat, lon, 500.0] for t in times]


def test_tracks_give_each_followers_distance_from_its_place_and_the_closest_two_vehicles_came() -> None:
    tracks = Tracks([track(0.0, 0.0, range(0, 50)), track(0.5, 5.0, range(0, 50)), track(0.0, 2.0, range(10, 20))])
    errors = tracks.formation_errors(1, (0.0, 5.0, 0.0), 1.0, 2.0)
    assert len(errors) == 11 and errors == pytest.approx([0.5] * 11, abs=1e-6)
    assert tracks.min_separation() == pytest.approx(2.0, abs=1e-6)


@pytest.mark.parametrize(
    "text",
    [
        '{"slot": 3, "vehicles": ["v1", "v2"], "spacing_m": 5}',
        '{"slot": 1, "vehicles": ["v 1"], "spacing_m": 5}',
        '{"slot": 1, "vehicles": ["v1"], "spacing_m": -1}',
        '{"slot": 1, "vehicles": []}',
        "[1]",
    ],
)
def test_a_malformed_swarm_role_is_refused(text: str) -> None:
    with pytest.raises(ValueError):
        swarm_role(text)


def test_a_swarm_role_names_the_leader() -> None:
    role = swarm_role(json.dumps({"slot": 2, "vehicles": ["a", "b"], "spacing_m": 4}))
    assert role.leader == "a" and not role.leads and role.spacing_m == 4.0
