"""Land Detector (PX4 ``src/modules/land_detector/land_detector_params_mc.c`` for a multicopter,
``land_detector_params_fw.c`` for a fixed-wing vehicle).

PX4 gives the multicopter thresholds, LNDFW_TRIG_TIME and LNDFW_ROT_MAX a minimum or nothing. Their maxima here
(a threshold that high would take a flying vehicle for a landed one): LNDMC_Z_VEL_MAX MPC_Z_VEL_MAX_DN's 4 m/s
(PX4 caps it lower still, at min(MPC_LAND_CRWL, MPC_LAND_SPEED) / 1.2); LNDMC_XY_VEL_MAX 10 m/s, PX4's bound of
the fixed-wing LNDFW_VEL_XY_MAX in ``land_detector_params_fw.c`` before it was raised to 20; the rotation
thresholds 90 deg/s, a quarter turn a second, which nothing standing on the ground shows (4.5 × PX4's default
LNDMC_ROT_MAX); LNDMC_ALT_GND 10 m, where ground effect (about a rotor diameter or two) is long gone;
LNDFW_TRIG_TIME PX4's bound of LNDMC_TRIG_TIME (10 s)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("LNDMC_TRIG_TIME", 1.0, 0.1, 10.0, "s", "Total time to go through ground contact, maybe landed, landed"),
    Param("LNDMC_Z_VEL_MAX", 0.25, 0.0, 4.0, "m/s", "Vertical speed below which the vehicle counts as still"),
    Param("LNDMC_XY_VEL_MAX", 1.5, 0.0, 10.0, "m/s", "Horizontal speed allowed in the landed state"),
    Param("LNDMC_ROT_MAX", 20.0, 0.0, 90.0, "deg/s", "Roll/pitch rate allowed in the landed state"),
    Param("LNDMC_ALT_GND", 2.0, -1.0, 10.0, "m", "Height below which ground effect is assumed (negative: none)"),
    Param("LNDFW_TRIG_TIME", 2.0, 0.1, 10.0, "s", "Fixed wing: how long the land conditions must hold"),
    Param("LNDFW_VEL_XY_MAX", 5.0, 0.5, 20.0, "m/s", "Fixed wing: ground speed allowed landed (×0.7 without airspeed)"),
    Param("LNDFW_VEL_Z_MAX", 1.0, 0.1, 20.0, "m/s", "Fixed wing: vertical speed allowed in the landed state"),
    Param("LNDFW_AIRSPD_MAX", 6.0, 2.0, 30.0, "m/s", "Fixed wing: airspeed allowed in the landed state"),
    Param("LNDFW_XYACC_MAX", 8.0, 2.0, 30.0, "m/s^2", "Fixed wing: horizontal acceleration allowed landed"),
    Param(
        "LNDFW_ROT_MAX",
        0.5,
        0.0,
        90.0,
        "deg/s",
        "Fixed wing: angular rate allowed in the landed state, used only without ground speed and airspeed",
    ),
)
