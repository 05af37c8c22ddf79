"""Geofence (PX4 ``src/modules/navigator/geofence_params.c``): the cylinder about home and its breach action."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param(
        "GF_ACTION",
        2,
        0,
        5,
        "",
        "Geofence violation action",
        values={0: "None", 1: "Warning", 2: "Hold mode", 3: "Return mode", 4: "Terminate", 5: "Land mode"},
    ),
    Param("GF_MAX_HOR_DIST", 0.0, 0.0, 10000.0, "m", "Maximum horizontal distance from home (0 = no limit)"),
    Param("GF_MAX_VER_DIST", 0.0, 0.0, 10000.0, "m", "Maximum height above home (0 = no limit)"),
)
