"""Mission (PX4 ``src/modules/navigator/navigator_params.c``, ``mission_params.c``): acceptance radii,
takeoff altitude, waypoint headings and the mission feasibility checks."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("NAV_ACC_RAD", 2.0, 0.05, 200.0, "m", "Horizontal acceptance radius (multicopter default)"),
    Param("NAV_MC_ALT_RAD", 0.8, 0.05, 200.0, "m", "Vertical acceptance radius (waypoints, the takeoff altitude)"),
    Param("NAV_FW_ALT_RAD", 10.0, 0.05, 200.0, "m", "Fixed-wing vertical acceptance radius (waypoints, takeoff)"),
    Param("NAV_LOITER_RAD", 80.0, 25.0, 1000.0, "m", "Fixed-wing loiter radius (Hold, Return, items giving none)"),
    Param(
        "MIS_TAKEOFF_ALT",
        2.5,
        0.0,
        80.0,
        "m",
        "Takeoff altitude above home when a takeoff gives none; a takeoff to an altitude outside this range is "
        "refused",
    ),
    Param("MIS_YAW_ERR", 12.0, 0.0, 90.0, "deg", "Yaw error within which a waypoint heading counts as reached"),
    Param("MIS_YAW_TMT", -1.0, -1.0, 20.0, "s", "Give up waiting for the heading after this long (−1: wait)"),
    Param(
        "MIS_DIST_1WP",
        900.0,
        0.0,
        10000.0,
        "m",
        "Largest distance of the first waypoint, and of a go-to target horizontally or vertically, from home "
        "(0: no limit)",
    ),
    Param("MIS_DIST_WPS", 900.0, 0.0, 10000.0, "m", "Largest distance between waypoints (0: no limit)"),
)
