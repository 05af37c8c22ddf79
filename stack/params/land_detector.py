"""Land Detector (PX4 ``src/modules/land_detector/land_detector_params_mc.c``)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("LNDMC_TRIG_TIME", 1.0, 0.1, 10.0, "s", "Total time to go through ground contact, maybe landed, landed"),
    Param("LNDMC_Z_VEL_MAX", 0.25, 0.0, None, "m/s", "Vertical speed below which the vehicle counts as still"),
    Param("LNDMC_XY_VEL_MAX", 1.5, 0.0, None, "m/s", "Horizontal speed allowed in the landed state"),
    Param("LNDMC_ROT_MAX", 20.0, 0.0, None, "deg/s", "Roll/pitch rate allowed in the landed state"),
    Param("LNDMC_ALT_GND", 2.0, -1.0, None, "m", "Height below which ground effect is assumed (negative: none)"),
)
