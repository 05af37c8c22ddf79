"""Return Mode (PX4 ``src/modules/navigator/rtl_params.c``).

Current PX4 gives RTL_RETURN_ALT, RTL_DESCEND_ALT, RTL_LAND_DELAY and RTL_MIN_DIST a minimum only; the maxima
here are the ones its ``rtl_params.c`` had before (the release with RTL_CONE_ANG and RTL_FLT_TIME): 150 m,
100 m, 300 s and 100 m."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("RTL_RETURN_ALT", 30.0, 0.0, 150.0, "m", "Return altitude above home (multicopter default)"),
    Param("RTL_DESCEND_ALT", 10.0, 0.0, 100.0, "m", "Altitude above home to descend to before landing"),
    Param("RTL_LAND_DELAY", 0.0, -1.0, 300.0, "s", "Wait at RTL_DESCEND_ALT before landing (−1: do not land)"),
    Param("RTL_MIN_DIST", 10.0, 0.5, 100.0, "m", "Within this distance of home the return altitude follows the cone"),
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
