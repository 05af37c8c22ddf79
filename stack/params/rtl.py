"""Return Mode (PX4 ``src/modules/navigator/rtl_params.c``)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("RTL_RETURN_ALT", 30.0, 0.0, None, "m", "Return altitude above home (multicopter default)"),
    Param("RTL_DESCEND_ALT", 10.0, 0.0, None, "m", "Altitude above home to descend to before landing"),
    Param("RTL_LAND_DELAY", 0.0, -1.0, None, "s", "Wait at RTL_DESCEND_ALT before landing (−1: do not land)"),
    Param("RTL_MIN_DIST", 10.0, 0.5, None, "m", "Within this distance of home the return altitude follows the cone"),
    Param(
        "RTL_CONE_ANG",
        45,
        0,
        90,
        "deg",
        "Half-angle of the return mode altitude cone",
        values={
            0: "No cone, always climb to RTL_RETURN_ALT above destination",
            25: "25 degrees half cone angle",
            45: "45 degrees half cone angle",
            65: "65 degrees half cone angle",
            80: "80 degrees half cone angle",
            90: "Only climb to at least RTL_DESCEND_ALT above destination",
        },
    ),
)
