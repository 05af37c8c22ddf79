"""Multicopter Rate Control (PX4 ``src/modules/mc_rate_control/mc_rate_control_params.c``), PX4's K-form:
the effective gains are K × P, I and D. Acro's stick-to-rate mapping is the attitude controller's here.

PX4 gives the I, FF and integrator-limit parameters, and the pitch and yaw D gains, a minimum only. Their
maxima here: I, FF and the integrator limit are ArduPilot's ranges for the same gains in the same units
(rad/s of rate error to normalised torque; ``libraries/AC_AttitudeControl/AC_AttitudeControl_Multi.cpp``:
ATC_RAT_RLL/PIT_I 0.01…2, ATC_RAT_YAW_I 0.01…1, ATC_RAT_*_FF 0…0.5, ATC_RAT_*_IMAX 0…1, the integrator being
normalised torque, which saturates at 1); the pitch and yaw D gains take PX4's bound of MC_ROLLRATE_D (0.01).
"""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("MC_ROLLRATE_P", 0.15, 0.01, 0.5, "", "Roll rate P gain (torque per rad/s of error)"),
    Param("MC_ROLLRATE_I", 0.2, 0.0, 2.0, "", "Roll rate I gain"),
    Param("MC_ROLLRATE_D", 0.003, 0.0, 0.01, "", "Roll rate D gain (on measured angular acceleration)"),
    Param("MC_ROLLRATE_FF", 0.0, 0.0, 0.5, "", "Roll rate feed-forward gain"),
    Param("MC_ROLLRATE_K", 1.0, 0.01, 5.0, "", "Roll rate controller gain multiplying P, I and D"),
    Param("MC_RR_INT_LIM", 0.3, 0.0, 1.0, "", "Roll rate integrator limit"),
    Param("MC_PITCHRATE_P", 0.15, 0.01, 0.6, "", "Pitch rate P gain"),
    Param("MC_PITCHRATE_I", 0.2, 0.0, 2.0, "", "Pitch rate I gain"),
    Param("MC_PITCHRATE_D", 0.003, 0.0, 0.01, "", "Pitch rate D gain"),
    Param("MC_PITCHRATE_FF", 0.0, 0.0, 0.5, "", "Pitch rate feed-forward gain"),
    Param("MC_PITCHRATE_K", 1.0, 0.01, 5.0, "", "Pitch rate controller gain multiplying P, I and D"),
    Param("MC_PR_INT_LIM", 0.3, 0.0, 1.0, "", "Pitch rate integrator limit"),
    Param("MC_YAWRATE_P", 0.2, 0.0, 0.6, "", "Yaw rate P gain"),
    Param("MC_YAWRATE_I", 0.1, 0.0, 1.0, "", "Yaw rate I gain"),
    Param("MC_YAWRATE_D", 0.0, 0.0, 0.01, "", "Yaw rate D gain"),
    Param("MC_YAWRATE_FF", 0.0, 0.0, 0.5, "", "Yaw rate feed-forward gain"),
    Param("MC_YAWRATE_K", 1.0, 0.01, 5.0, "", "Yaw rate controller gain multiplying P, I and D"),
    Param("MC_YR_INT_LIM", 0.3, 0.0, 1.0, "", "Yaw rate integrator limit"),
    Param("MC_YAW_TQ_CUTOFF", 2.0, 0.0, 10.0, "Hz", "Yaw torque low-pass cutoff (0 = off)"),
    Param("MC_ACRO_R_MAX", 100.0, 0.0, 1800.0, "deg/s", "Acro roll rate at full stick"),
    Param("MC_ACRO_P_MAX", 100.0, 0.0, 1800.0, "deg/s", "Acro pitch rate at full stick"),
    Param("MC_ACRO_Y_MAX", 100.0, 0.0, 1800.0, "deg/s", "Acro yaw rate at full stick"),
    Param("MC_ACRO_EXPO", 0.0, 0.0, 1.0, "", "Acro roll/pitch expo (0 linear … 1 cubic)"),
    Param("MC_ACRO_EXPO_Y", 0.0, 0.0, 1.0, "", "Acro yaw expo"),
    Param("MC_ACRO_SUPEXPO", 0.0, 0.0, 0.95, "", "Acro roll/pitch super-expo (0 = off)"),
    Param("MC_ACRO_SUPEXPOY", 0.0, 0.0, 0.95, "", "Acro yaw super-expo (0 = off)"),
)
