"""Airspeed selector: checks and wind estimator (PX4 v1.13
``src/modules/airspeed_selector/airspeed_selector_params.c``)."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    Param("ASPD_W_P_NOISE", 0.1, 0.0, 1.0, "m/s^2", "Wind estimator: wind process noise"),
    Param("ASPD_SC_P_NOISE", 0.0001, 0.0, 0.1, "1/s", "Wind estimator: true airspeed scale process noise"),
    Param("ASPD_TAS_NOISE", 1.4, 0.0, 4.0, "m/s", "Wind estimator: true airspeed measurement noise"),
    Param("ASPD_BETA_NOISE", 0.3, 0.0, 1.0, "rad", "Wind estimator: sideslip measurement noise"),
    Param("ASPD_TAS_GATE", 3, 1, 5, "SD", "Wind estimator: true airspeed innovation gate"),
    Param("ASPD_BETA_GATE", 1, 1, 5, "SD", "Wind estimator: sideslip innovation gate"),
    Param(
        "ASPD_DO_CHECKS",
        1,
        0,
        1,
        "",
        "Check the airspeed in flight (innovation and load factor); a missing sensor is always detected",
        values=ENABLED,
    ),
    Param(
        "ASPD_FS_INNOV",
        1.0,
        0.5,
        3.0,
        "",
        "Airspeed innovation test ratio above which the inconsistency is integrated toward a failure",
    ),
    Param(
        "ASPD_FS_INTEG",
        5.0,
        -1.0,
        30.0,
        "s",
        "Integral of the test ratio's excess that fails the innovation check (<= 0: any excess)",
    ),
    Param("ASPD_FS_T_STOP", 2, 1, 10, "s", "Delay before a failing airspeed is declared invalid"),
    Param(
        "ASPD_FS_T_START",
        -1,
        -1,
        1000,
        "s",
        "Delay before an airspeed whose checks pass again is used again (negative: never, in flight)",
    ),
)
