"""Land Detector (PX4 ``src/modules/land_detector/land_detector_params_mc.c`` for a multicopter,
``land_detector_params_fw.c`` for a fixed-wing vehicle)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("LNDMC_TRIG_TIME", 1.0, 0.1, 10.0, "s", "Total time to go through ground contact, maybe landed, landed"),
    Param("LNDMC_Z_VEL_MAX", 0.25, 0.0, None, "m/s", "Vertical speed below which the vehicle counts as still"),
    Param("LNDMC_XY_VEL_MAX", 1.5, 0.0, None, "m/s", "Horizontal speed allowed in the landed state"),
    Param("LNDMC_ROT_MAX", 20.0, 0.0, None, "deg/s", "Roll/pitch rate allowed in the landed state"),
    Param("LNDMC_ALT_GND", 2.0, -1.0, None, "m", "Height below which ground effect is assumed (negative: none)"),
    Param("LNDFW_TRIG_TIME", 2.0, 0.1, None, "s", "Fixed wing: how long the land conditions must hold"),
    Param("LNDFW_VEL_XY_MAX", 5.0, 0.5, 20.0, "m/s", "Fixed wing: ground speed allowed landed (×0.7 without airspeed)"),
    Param("LNDFW_VEL_Z_MAX", 1.0, 0.1, 20.0, "m/s", "Fixed wing: vertical speed allowed in the landed state"),
    Param("LNDFW_AIRSPD_MAX", 6.0, 2.0, 30.0, "m/s", "Fixed wing: airspeed allowed in the landed state"),
    Param("LNDFW_XYACC_MAX", 8.0, 2.0, 30.0, "m/s^2", "Fixed wing: horizontal acceleration allowed landed"),
    Param(
        "LNDFW_ROT_MAX",
        0.5,
        0.0,
        None,
        "deg/s",
        "Fixed wing: angular rate allowed in the landed state, used only without ground speed and airspeed",
    ),
)
