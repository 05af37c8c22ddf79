"""What `stack cmd --wait` makes of the vehicle's messages: done, failed (failsafe, disarmed, another mode,
not where asked), progress, and the time each action may take."""

import math

import pytest

from stack.cli.follow import (
    BUDGET_FLOOR_S,
    GOTO_MODES,
    LAND_MODES,
    MISSION_MODES,
    PARAMS,
    RETURN_MODES,
    TAKEOFF_MODES,
    Goto,
    Land,
    MissionRun,
    Progress,
    Return,
    Takeoff,
    Vehicle,
    budget_s,
)
from stack.mission.items import Mission, MissionItem
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.system import HomePosition, MavlinkLog, VehicleStatus
from stack.params import catalogue

NS = VehicleStatus
P = {name: float(catalogue.get(name).default) for name in PARAMS}
ARMED, DISARMED = NS.ARMING_STATE_ARMED, NS.ARMING_STATE_DISARMED


def vehicle(nav_state: int, z: float, *, armed: bool = True, failsafe: bool = False, x: float = 0.0) -> Vehicle:
    v = Vehicle()
    v.update("home_position", HomePosition(timestamp=1, valid_lpos=True, z=0.5))
    v.update("vehicle_local_position", VehicleLocalPosition(timestamp=2_000_000, x=x, z=z))
    status = NS(timestamp=2_000_000, nav_state=nav_state, arming_state=ARMED if armed else DISARMED, failsafe=failsafe)
    v.update("vehicle_status", status)
    return v


def test_the_vehicle_clock_and_what_it_said():
    v = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, -4.5)
    v.update("mavlink_log", MavlinkLog(timestamp=3_000_000, text="Armed", severity=MavlinkLog.SEVERITY_INFO))
    v.update("mavlink_log", MavlinkLog(timestamp=3_500_000, text="Failsafe activated (x)", severity=2))
    assert v.now_us == 3_500_000 and v.said == "Failsafe activated (x)"
    assert v.height() == 5.0 and v.describe() == "altitude 5.0 m, Hold"


def test_takeoff_is_done_at_the_altitude_not_by_the_mode():
    takeoff = Takeoff("takeoff", TAKEOFF_MODES, p=P, height_m=5.0)
    on_ground = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, 0.5)
    assert takeoff.done(on_ground) is None and takeoff.failed(on_ground) is None
    assert takeoff.progress(on_ground) == "altitude 0.0 m, Hold of 5.0 m"
    climbing = vehicle(NS.NAVIGATION_STATE_AUTO_TAKEOFF, -4.0)
    assert takeoff.done(climbing) is None
    there = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, -4.0)
    assert takeoff.done(there) == "takeoff complete: altitude 4.5 m, Hold"
    # MIS_TAKEOFF_ALT when no altitude is given.
    assert Takeoff("takeoff", TAKEOFF_MODES, p=P).target() == P["MIS_TAKEOFF_ALT"]


def test_a_failsafe_fails_the_action_with_what_the_vehicle_said():
    takeoff = Takeoff("takeoff", TAKEOFF_MODES, p=P, height_m=5.0)
    held = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, 0.5, failsafe=True)
    # The state may come before the commander's word on the cause (two topics): the follower waits for it.
    held.said = "Failsafe warning: battery low"
    assert not held.failsafe_explained()
    held.said = "Failsafe activated (battery_critical): Hold"
    assert held.failsafe_explained()
    assert takeoff.failed(held) == (
        "takeoff failed: a failsafe took over (Hold): Failsafe activated (battery_critical): Hold"
    )
    disarmed = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, 0.5, armed=False)
    assert takeoff.failed(disarmed) == "takeoff failed: the vehicle disarmed"
    other = vehicle(NS.NAVIGATION_STATE_POSCTL, -3.0)
    assert takeoff.failed(other) == "takeoff interrupted: now in Position"


def test_goto_is_done_within_a_metre():
    goto = Goto("goto", GOTO_MODES, p=P, target=lambda _: (10.0, 0.0, -5.0))
    far = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, -5.0)
    assert goto.done(far) is None and goto.progress(far) == "10.0 m to go, altitude 5.5 m, Hold"
    assert goto.nominal_s(far) == pytest.approx(10.0 / P["MPC_XY_CRUISE"])
    assert goto.done(vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, -5.0, x=9.5)).startswith("goto: reached")
    assert goto.failed(vehicle(NS.NAVIGATION_STATE_AUTO_RTL, -5.0)) == "goto interrupted: now in Return"


def test_land_and_return_end_disarmed_and_a_return_at_home():
    land = Land("land", LAND_MODES, ends_disarmed=True, p=P)
    assert land.done(vehicle(NS.NAVIGATION_STATE_AUTO_LAND, -3.0)) is None
    down = vehicle(NS.NAVIGATION_STATE_AUTO_LAND, 0.5, armed=False)
    assert land.failed(down) is None and land.done(down) == "land: landed and disarmed"
    rtl = Return("rtl", RETURN_MODES, ends_disarmed=True, p=P)
    home = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, 0.5, armed=False, x=0.4)
    assert rtl.failed(home) is None and rtl.done(home) == "rtl: landed at home (0.4 m off) and disarmed"
    away = vehicle(NS.NAVIGATION_STATE_AUTO_RTL, 0.5, armed=False, x=20.0)
    assert rtl.failed(away) == "rtl failed: disarmed 20.0 m from home" and rtl.done(away) is None


def test_a_planes_return_ends_on_the_runway_it_took_off_from_not_at_home():
    rtl = Return("rtl", RETURN_MODES, ends_disarmed=True, p=P)

    def plane_at(north: float, east: float) -> Vehicle:
        v = Vehicle()
        v.update("home_position", HomePosition(timestamp=1, valid_lpos=True, x=10.0, y=20.0, yaw=0.5 * math.pi))
        v.update("vehicle_local_position", VehicleLocalPosition(timestamp=2_000_000, x=north, y=east))
        status = NS(timestamp=2_000_000, arming_state=DISARMED, vehicle_type=NS.VEHICLE_TYPE_FIXED_WING)
        v.update("vehicle_status", status)
        return v

    rolled_out = plane_at(12.0, 208.7)  # 188.7 m along the eastbound runway from home, 2 m left of its centre
    assert rtl.failed(rolled_out) is None
    assert (
        rtl.done(rolled_out)
        == "rtl: landed on the runway (189 m along the runway, 2.0 m off its centre line) and disarmed"
    )
    beside = plane_at(40.0, 120.0)
    assert rtl.done(beside) is None
    assert (
        rtl.failed(beside) == "rtl failed: disarmed off the runway (100 m along the runway, 30.0 m off its centre line)"
    )


def test_budgets_follow_the_distances_and_the_speed_parameters():
    assert budget_s(0.0) == BUDGET_FLOOR_S and budget_s(-5.0) == BUDGET_FLOOR_S
    high = vehicle(NS.NAVIGATION_STATE_AUTO_LAND, -28.5)  # 29 m above home
    land = Land("land", LAND_MODES, ends_disarmed=True, p=P)
    assert land.nominal_s(high) == pytest.approx(29.0 / P["MPC_LAND_SPEED"] + P["COM_DISARM_LAND"])
    assert budget_s(land.nominal_s(high)) > 100.0  # where 5 s of wall time was not enough
    rtl = Return("rtl", RETURN_MODES, ends_disarmed=True, p=P)
    far = vehicle(NS.NAVIGATION_STATE_AUTO_RTL, -4.5, x=100.0)  # 5 m up, 100 m out
    climb = (P["RTL_RETURN_ALT"] - 5.0) / P["MPC_Z_V_AUTO_UP"]
    descend = (P["RTL_RETURN_ALT"] - P["RTL_DESCEND_ALT"]) / P["MPC_Z_V_AUTO_DN"]
    landing = P["RTL_DESCEND_ALT"] / P["MPC_LAND_SPEED"] + P["COM_DISARM_LAND"]
    assert rtl.nominal_s(far) == pytest.approx(100.0 / P["MPC_XY_CRUISE"] + climb + descend + landing)


def item(command: int, north: float = math.nan, east: float = math.nan, down: float = math.nan) -> MissionItem:
    return MissionItem(index=0, command=command, frame=1, north=north, east=east, down=down)


def test_a_mission_until_its_end_and_landing():
    mission = Mission((item(22, down=-10.0), item(16, 20.0, 0.0, -10.0), item(21)))
    run = MissionRun("mission", MISSION_MODES, p=P, mission=mission, mission_id=9, started_us=1_000_000)
    v = vehicle(NS.NAVIGATION_STATE_AUTO_MISSION, 0.5)
    expected = 10.0 / P["MPC_TKO_SPEED"] + 20.0 / P["MPC_XY_CRUISE"] + 10.0 / P["MPC_LAND_SPEED"]
    assert run.nominal_s(v) == pytest.approx(expected + P["COM_DISARM_LAND"])
    v.update("mission_result", MissionResult(timestamp=900_000, mission_id=9, finished=True, seq_total=3))
    assert run.done(v) is None  # a result from before the start
    v.update("mission_result", MissionResult(timestamp=2_000_000, mission_id=9, seq_current=1, seq_total=3))
    assert run.progress(v) == "item 2/3, altitude 0.0 m, Mission" and run.done(v) is None
    v.update("mission_result", MissionResult(timestamp=3_000_000, mission_id=9, finished=True, seq_total=3))
    assert run.done(v) is None and run.failed(v) is None  # landing
    v.update("vehicle_status", NS(timestamp=4_000_000, nav_state=NS.NAVIGATION_STATE_AUTO_LOITER))
    assert run.done(v) == "mission finished, landed and disarmed"


def test_a_mission_that_fails_or_is_left():
    mission = Mission((item(16, 5.0, 0.0, -5.0),))
    run = MissionRun("mission", MISSION_MODES, p=P, mission=mission, mission_id=4)
    v = vehicle(NS.NAVIGATION_STATE_AUTO_LOITER, -4.5)
    assert run.failed(v) == "mission interrupted: now in Hold"
    v.update("mission_result", MissionResult(timestamp=3_000_000, mission_id=4, failure=True, reason="too far"))
    assert run.failed(v) == "mission failed: too far"
    v.update("mission_result", MissionResult(timestamp=4_000_000, mission_id=4, finished=True))
    assert run.failed(v) is None and run.done(v) == "mission finished"


def test_progress_is_printed_when_it_changes_and_now_and_then_when_it_does_not():
    progress = Progress(heartbeat_s=10.0)
    printed = [
        t
        for t, line in (
            (0, "item 1/8"),
            (1, "item 1/8"),
            (2, "item 2/8"),
            (3, "item 2/8"),
            (11, "item 2/8"),
            (12, "item 2/8"),
            (21, "item 2/8"),
            (22, "item 3/8"),
        )
        if progress.due(line, t)
    ]
    assert printed == [0, 2, 12, 22]  # the heartbeat counts from the last line printed
    assert progress.line == "item 3/8"
