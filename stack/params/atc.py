"""ArduPilot's attitude input shaping (``libraries/AC_AttitudeControl/AC_AttitudeControl.cpp``), the front end
the attitude controller uses when MC_INPUT_SHAPING is 1; ArduPilot's names and units."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    Param("ATC_INPUT_TC", 0.15, 0.0, 1.0, "s", "Attitude input time constant (0.5 very soft … 0.05 very crisp)"),
    Param("ATC_ACCEL_R_MAX", 110000.0, 0.0, 180000.0, "cdeg/s/s", "Roll acceleration limit (0 = off)"),
    Param("ATC_ACCEL_P_MAX", 110000.0, 0.0, 180000.0, "cdeg/s/s", "Pitch acceleration limit (0 = off)"),
    Param("ATC_ACCEL_Y_MAX", 27000.0, 0.0, 72000.0, "cdeg/s/s", "Yaw acceleration limit (0 = off)"),
    Param(
        "ATC_RATE_FF_ENAB",
        1,
        0,
        1,
        "",
        "Rate feed-forward: shape the inputs and feed the target rate forward (else jump to the desired attitude)",
        values=ENABLED,
    ),
    Param("ATC_SLEW_YAW", 6000.0, 500.0, 18000.0, "cdeg/s", "Yaw slew limit for slewed yaw-angle inputs"),
    Param("ATC_RATE_R_MAX", 0.0, 0.0, 1080.0, "deg/s", "Roll target-rate limit (0 = off)"),
    Param("ATC_RATE_P_MAX", 0.0, 0.0, 1080.0, "deg/s", "Pitch target-rate limit (0 = off)"),
    Param("ATC_RATE_Y_MAX", 0.0, 0.0, 1080.0, "deg/s", "Yaw target-rate limit (0 = off)"),
    Param("ACRO_RP_RATE_TC", 0.0, 0.0, 1.0, "s", "Body-rate input time constant, roll and pitch (0 = off)"),
    Param("ACRO_Y_RATE_TC", 0.0, 0.0, 1.0, "s", "Body-rate input time constant, yaw (0 = off)"),
)
