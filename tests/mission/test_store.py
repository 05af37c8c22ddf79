"""A mission flies its global items at their coordinates, wherever home was when it came (PX4's navigator): home
is set again at arming, after the upload, and a mission planned about the old home must not move with it."""

import math

import pytest

from stack.commander.home import home_from_local_position
from stack.mathlib.geo import MapProjection
from stack.mission.items import MAV_CMD_NAV_WAYPOINT as WAYPOINT
from stack.mission.items import GeoPoint, Mission, about_home, item_from_mavlink
from stack.mission.store import MissionStore

REF = (47.397742, 8.545594, 488.0)  # the local frame's reference point (lat, lon, alt)
PLANNED_HOME = GeoPoint(47.397742, 8.545594, 488.0)
GLOBAL_AMSL, GLOBAL_RELATIVE, LOCAL_NED = 0, 3, 1


def mission() -> Mission:
    corner = MapProjection(PLANNED_HOME.lat, PLANNED_HOME.lon).reproject(20.0, 10.0)
    items = (
        item_from_mavlink(0, WAYPOINT, GLOBAL_RELATIVE, (0, 0, 0, math.nan, *corner, 10.0), True, PLANNED_HOME),
        item_from_mavlink(1, WAYPOINT, GLOBAL_AMSL, (0, 0, 0, math.nan, *corner, 498.0), True, PLANNED_HOME),
        item_from_mavlink(2, WAYPOINT, LOCAL_NED, (0, 0, 0, math.nan, 5.0, 5.0, -10.0), True, PLANNED_HOME),
    )
    return Mission(items, PLANNED_HOME)


def test_global_items_keep_their_place_about_a_new_home():
    # Home set again 3 m north and 4 m east of the planned one, 1 m higher.
    lat, lon = MapProjection(PLANNED_HOME.lat, PLANNED_HOME.lon).reproject(3.0, 4.0)
    moved = about_home(mission(), GeoPoint(lat, lon, 489.0))
    relative, amsl, local = moved.items
    assert (relative.north, relative.east, relative.down) == pytest.approx((17.0, 6.0, -10.0), abs=1e-3)
    assert (amsl.north, amsl.east, amsl.down) == pytest.approx((17.0, 6.0, -9.0), abs=1e-3)
    assert local.position == (5.0, 5.0, -10.0)  # local items are about home by definition
    assert about_home(moved, moved.home) is moved


def test_the_store_places_the_mission_about_the_home_it_starts_from():
    store = MissionStore()
    assert store.load(mission(), 1, {}) == ""
    # The vehicle armed 3 m north and 4 m east of where the mission was planned, 1 m higher.
    home = home_from_local_position(3.0, 4.0, -1.0, 0.0, *REF)
    progress = store.start(0, (3.0, 4.0, -1.0), 0, home)
    assert progress.target == pytest.approx((20.0, 10.0, -11.0), abs=1e-3)  # the corner itself, 10 m above home
    assert store.mission is not None and store.mission.home == GeoPoint(home.lat, home.lon, home.alt)
    # Without a geodetic home (no GPS reference) the items stay about home.
    store = MissionStore()
    store.load(mission(), 2, {})
    assert store.start(0, (3.0, 4.0, -1.0), 0, home._replace(lat=math.nan)).target == pytest.approx((23.0, 14.0, -11.0))
