"""Simulator (PX4 ``src/modules/simulation/simulator_sih/sih_params.c`` for SIH_LOC_*; ``SIM_GPS_USED`` and
the battery's ``SIM_BAT_*`` after PX4's SITL; the wind after ArduPilot's ``SIM_WIND_*``)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("SIH_LOC_LAT0", 47.397742, -90.0, 90.0, "deg", "Home latitude (applies at start)"),
    Param("SIH_LOC_LON0", 8.545594, -180.0, 180.0, "deg", "Home longitude (applies at start)"),
    Param("SIH_LOC_H0", 489.4, -420.0, 8848.0, "m", "Home altitude AMSL (applies at start)"),
    Param("SIM_GPS_USED", 10, 0, 50, "", "Satellites in view; fewer than 4 means no fix (GPS loss injection)"),
    Param("SIM_WIND_SPD", 0.0, 0.0, 40.0, "m/s", "Mean wind speed (ArduPilot SIM_WIND_SPD)"),
    Param("SIM_WIND_DIR", 0.0, 0.0, 360.0, "deg", "Direction the wind blows from (ArduPilot SIM_WIND_DIR)"),
    Param("SIM_WIND_GUST", 0.0, 0.0, 20.0, "m/s", "Horizontal gust standard deviation"),
    Param("SIM_WIND_GUST_T", 2.0, 0.1, 60.0, "s", "Gust correlation time"),
    Param(
        "SIM_WIND_HREF",
        0.0,
        0.0,
        100.0,
        "m",
        "Height the wind figures hold at; below it the wind falls off logarithmically to the ground (0: the same "
        "wind at every height)",
    ),
    # PX4's bound in src/modules/simulator/simulator_params.c (a day); 0 is the stack's (the charge kept).
    Param("SIM_BAT_DRAIN", 60.0, 0.0, 86400.0, "s", "Timed drain: full to empty while armed (0: no drain)"),
    Param("SIM_BAT_MIN_PCT", 50.0, 0.0, 100.0, "%", "The simulated charge never falls below this"),
)
