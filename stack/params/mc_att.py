"""Multicopter Attitude Control (PX4 ``src/modules/mc_att_control/mc_att_control_params.c``), with the
stack's choice of attitude setpoint front end (MC_INPUT_SHAPING, see :mod:`stack.params.atc`)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("MC_ROLL_P", 4.0, 0.0, 12.0, "1/s", "Roll P gain: rate setpoint per radian of roll error"),
    Param("MC_PITCH_P", 4.0, 0.0, 12.0, "1/s", "Pitch P gain"),
    Param("MC_YAW_P", 2.8, 0.0, 5.0, "1/s", "Yaw P gain"),
    Param("MC_YAW_WEIGHT", 0.4, 0.0, 1.0, "", "Fraction of the yaw error kept in the reduced-attitude law"),
    Param("MC_ROLLRATE_MAX", 220.0, 0.0, 1800.0, "deg/s", "Roll rate setpoint limit"),
    Param("MC_PITCHRATE_MAX", 220.0, 0.0, 1800.0, "deg/s", "Pitch rate setpoint limit"),
    Param("MC_YAWRATE_MAX", 200.0, 0.0, 1800.0, "deg/s", "Yaw rate setpoint limit"),
    Param("MC_MAN_TILT_TAU", 0.0, 0.0, 2.0, "s", "Roll/pitch stick filter time constant (0 = off)"),
    Param("MC_RATT_TH", 0.8, 0.01, 1.0, "", "Rattitude: roll/pitch stick deflection beyond which sticks command rates"),
    Param(
        "MC_INPUT_SHAPING",
        0,
        0,
        1,
        "",
        "Attitude setpoint front end (the stack's own parameter)",
        values={0: "PX4 (step)", 1: "ArduPilot input shaping"},
    ),
)
