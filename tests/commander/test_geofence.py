import math

from stack.commander.geofence import CylinderGeofence, GeofenceAction

HOME = (10.0, -5.0, -1.0)


def test_disabled_by_default():
    fence = CylinderGeofence()
    assert not fence.enabled
    assert fence.action == GeofenceAction.HOLD
    assert fence.inside(HOME, 1e6, 1e6, -1e4)


def test_cylinder_about_home():
    fence = CylinderGeofence({"GF_MAX_HOR_DIST": 100.0, "GF_MAX_VER_DIST": 30.0, "GF_ACTION": 3})
    assert fence.action == GeofenceAction.RETURN
    assert fence.inside(HOME, 10.0 + 60.0, -5.0 + 80.0, -30.0)
    assert "100.5 m from home" in fence.violation(HOME, 10.0 + 60.3, -5.0 + 80.4, -2.0)
    assert fence.inside(HOME, 10.0, -5.0, -31.0)
    assert "31.5 m above home" in fence.violation(HOME, 10.0, -5.0, -32.5)
    # Below home is never a breach, nor an unknown coordinate.
    assert fence.inside(HOME, 10.0, -5.0, 50.0)
    assert fence.inside(HOME, math.nan, math.nan, math.nan)


def test_each_limit_alone():
    only_height = CylinderGeofence({"GF_MAX_VER_DIST": 10.0})
    assert only_height.inside(HOME, 1e5, 0.0, -10.0)
    assert not only_height.inside(HOME, 0.0, 0.0, -12.0)
