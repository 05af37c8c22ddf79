import math

import pytest

from stack.commander.home import HomePosition, home_from_local_position
from stack.commander.rtl import ReturnToLaunch, RtlPhase

HOME = HomePosition(0.0, 0.0, 0.0, 0.5)


def test_return_altitude_cone_and_floors():
    rtl = ReturnToLaunch()
    assert rtl.return_altitude((100.0, 0.0, -5.0), HOME) == 30.0
    assert rtl.return_altitude((100.0, 0.0, -45.0), HOME) == 45.0
    # Inside RTL_MIN_DIST the 45° cone lowers it to the distance, but not below 2 × NAV_ACC_RAD.
    assert rtl.return_altitude((8.0, 0.0, -1.0), HOME) == pytest.approx(8.0)
    assert rtl.return_altitude((3.0, 0.0, -1.0), HOME) == pytest.approx(4.0)
    # Within the acceptance radius: twice the distance.
    assert rtl.return_altitude((1.0, 0.0, -0.5), HOME) == pytest.approx(2.0)
    assert ReturnToLaunch({"RTL_CONE_ANG": 0}).return_altitude((8.0, 0.0, -1.0), HOME) == 30.0


def test_phases_climb_return_descend_loiter_land():
    rtl = ReturnToLaunch({"RTL_LAND_DELAY": 2.0})
    sp = rtl.start(0, (100.0, 50.0, -10.0), HOME)
    assert sp.phase == RtlPhase.CLIMB and sp.position == (100.0, 50.0, -30.0) and math.isnan(sp.yaw)
    sp = rtl.update(1_000_000, (100.0, 50.0, -29.5), False)
    assert sp.phase == RtlPhase.RETURN and sp.position == (0.0, 0.0, -30.0)
    assert sp.yaw == pytest.approx(math.atan2(-50.0, -100.0))
    sp = rtl.update(2_000_000, (1.0, 1.0, -30.0), False)
    assert sp.phase == RtlPhase.DESCEND and sp.position == (0.0, 0.0, -10.0) and sp.yaw == 0.5
    sp = rtl.update(3_000_000, (0.0, 0.0, -10.5), False)
    assert sp.phase == RtlPhase.LOITER
    assert rtl.update(4_900_000, (0.0, 0.0, -10.0), False).phase == RtlPhase.LOITER
    sp = rtl.update(5_000_000, (0.0, 0.0, -10.0), False)
    assert sp.phase == RtlPhase.LAND and math.isnan(sp.position[2])
    assert rtl.update(9_000_000, (0.0, 0.0, 0.0), True).phase == RtlPhase.LANDED


def test_land_delay_minus_one_never_lands():
    rtl = ReturnToLaunch({"RTL_LAND_DELAY": -1.0})
    rtl.start(0, (0.0, 0.0, -10.0), HOME)
    rtl.update(1, (0.0, 0.0, -10.0), False)
    assert rtl.update(3_600_000_000, (0.0, 0.0, -10.0), False).phase == RtlPhase.LOITER


def test_low_return_altitude_is_kept_for_the_descent():
    rtl = ReturnToLaunch({"RTL_LAND_DELAY": 1.0})
    sp = rtl.start(0, (3.0, 0.0, -4.0), HOME)
    assert sp.position[2] == pytest.approx(-4.0)
    sp = rtl.update(1, (0.0, 0.0, -4.0), False)
    assert sp.phase == RtlPhase.LOITER and sp.position[2] == pytest.approx(-4.0)


def test_home_from_local_position():
    home = home_from_local_position(0.0, 0.0, -2.0, 0.3, 47.0, 8.0, 400.0)
    assert (home.lat, home.lon, home.alt) == (47.0, 8.0, 402.0)
    assert home.global_valid
    local_only = home_from_local_position(1.0, 2.0, 3.0, math.nan, math.nan, math.nan, math.nan)
    assert not local_only.global_valid and local_only.yaw == 0.0
