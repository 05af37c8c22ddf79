import math

import pytest

from stack.mission.items import MAV_CMD_NAV_LAND, MAV_CMD_NAV_WAYPOINT
from stack.mission.tracker import MissionTracker
from stack.mission.waypoints import parse_waypoint_list

MISSION = parse_waypoint_list(
    """\
takeoff 5
10 0 -5
speed 4
10 10 -5 90 2
land
"""
)
HOME = (1.0, 1.0, -0.5)


def _at(offset, down):
    return (HOME[0] + offset[0], HOME[1] + offset[1], down)


def test_progress_through_a_mission():
    tracker = MissionTracker(MISSION)
    p = tracker.start(0, HOME, home_ned=HOME)
    assert (p.seq_current, p.seq_reached, p.seq_total, p.finished) == (0, -1, 5, False)
    assert p.target == (1.0, 1.0, -5.5)  # takeoff over the start position, 5 m above home
    assert tracker.update(1, _at((0, 0), -4.0), 0.0, False).seq_current == 0
    p = tracker.update(2, _at((0, 0), -4.8), 0.0, False)
    assert (p.seq_current, p.seq_reached) == (1, 0)
    assert p.target == (11.0, 1.0, -5.5) and p.previous == (1.0, 1.0, -5.5)
    assert p.command == MAV_CMD_NAV_WAYPOINT and math.isnan(p.cruise_speed)

    # Within NAV_ACC_RAD (2 m) and NAV_MC_ALT_RAD (0.8 m): the speed item applies at once.
    assert tracker.update(3, _at((7.5, 0), -5.5), 0.0, False).seq_current == 1
    p = tracker.update(4, _at((8.5, 0.5), -6.0), 0.0, False)
    assert (p.seq_current, p.seq_reached, p.cruise_speed) == (3, 2, 4.0)
    assert p.target == (11.0, 11.0, -5.5) and p.target_yaw == pytest.approx(math.pi / 2)

    # Position reached at t = 10 s but heading still wrong; aligned at 11 s; the 2 s hold ends at 13 s.
    t = 10_000_000
    assert tracker.update(t, _at((10, 10), -5.5), 0.0, False).seq_current == 3
    assert tracker.update(t + 1_000_000, _at((15, 15), -5.5), math.radians(85), False).seq_current == 3
    assert tracker.update(t + 2_999_000, _at((15, 15), -5.5), math.radians(85), False).seq_current == 3
    p = tracker.update(t + 3_000_000, _at((15, 15), -5.5), math.radians(85), False)
    assert (p.seq_current, p.seq_reached, p.command) == (4, 3, MAV_CMD_NAV_LAND)
    assert p.target[:2] == (16.0, 16.0) and math.isnan(p.target[2])

    assert not tracker.update(t + 4_000_000, _at((15, 15), -1.0), 0.0, False).finished
    p = tracker.update(t + 5_000_000, _at((15, 15), 0.0), 0.0, True)
    assert p.finished and p.seq_reached == 4


def test_yaw_timeout():
    tracker = MissionTracker(parse_waypoint_list("0 0 -5 90\n5 0 -5\n"), {"MIS_YAW_TMT": 1.0})
    tracker.start(0, (0.0, 0.0, -5.0))
    tracker.update(0, (0.0, 0.0, -5.0), 0.0, False)
    assert tracker.update(999_999, (0.0, 0.0, -5.0), 0.0, False).seq_current == 0
    assert tracker.update(1_000_000, (0.0, 0.0, -5.0), 0.0, False).seq_current == 1


def test_item_acceptance_radius_overrides_nav_acc_rad():
    tracker = MissionTracker(parse_waypoint_list("10 0 -5 - 0 0.5\n20 0 -5\n"))
    tracker.start(0, (0.0, 0.0, -5.0))
    assert tracker.update(1, (9.0, 0.0, -5.0), 0.0, False).seq_current == 0
    assert tracker.update(2, (9.6, 0.0, -5.0), 0.0, False).seq_current == 1


def test_last_waypoint_finishes_and_holds_there():
    tracker = MissionTracker(parse_waypoint_list("5 0 -5\n"))
    tracker.start(0, (0.0, 0.0, -5.0))
    p = tracker.update(1, (5.0, 0.0, -5.0), 0.0, False)
    assert p.finished and p.seq_reached == 0 and p.target == (5.0, 0.0, -5.0)
    assert tracker.update(2, (50.0, 0.0, -5.0), 0.0, False).finished


def test_return_item_requests_return_mode():
    tracker = MissionTracker(parse_waypoint_list("5 0 -5\nrtl\n"))
    tracker.start(0, (0.0, 0.0, -5.0))
    p = tracker.update(1, (5.0, 0.0, -5.0), 0.0, False)
    assert p.return_requested and p.finished and p.seq_reached == 1


def test_unlimited_loiter_is_never_left():
    tracker = MissionTracker(parse_waypoint_list("loiter 5 0 -5\n10 0 -5\n"))
    tracker.start(0, (0.0, 0.0, -5.0))
    p = tracker.update(1, (5.0, 0.0, -5.0), 0.0, False)
    assert (p.seq_current, p.seq_reached, p.finished) == (0, 0, False)
    assert tracker.update(600_000_000, (5.0, 0.0, -5.0), 0.0, False).seq_current == 0


def test_start_at_an_item_and_resume():
    tracker = MissionTracker(MISSION)
    p = tracker.start(0, (0.0, 0.0, -5.0), first_index=3)
    assert p.seq_current == 3 and p.previous == (0.0, 0.0, -5.0)
    assert tracker.start(0, (0.0, 0.0, -5.0), first_index=-1).seq_current == 3
    with pytest.raises(ValueError, match="outside 0…4"):
        tracker.start(0, (0.0, 0.0, 0.0), first_index=5)
    with pytest.raises(ValueError, match="empty mission"):
        MissionTracker(()).start(0, (0.0, 0.0, 0.0))
