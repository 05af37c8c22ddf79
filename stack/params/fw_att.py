"""Fixed-wing attitude control (PX4 ``src/modules/fw_att_control/fw_att_control_params.c``) and the figures
every fixed-wing module reads: the airspeeds (FW_AIRSPD_*), the attitude limits (FW_R_LIM, FW_P_LIM_*) and
the throttle range (FW_THR_*, ``fw_pos_control_params.c``)."""

from stack.params.param import Param

SHARED: tuple[Param, ...] = (
    Param("FW_AIRSPD_MIN", 10.0, 0.5, 100.0, "m/s", "Minimum airspeed (the slowest the controllers command)"),
    Param("FW_AIRSPD_TRIM", 15.0, 0.5, 100.0, "m/s", "Cruise (trim) airspeed"),
    Param("FW_AIRSPD_MAX", 20.0, 0.5, 100.0, "m/s", "Maximum airspeed"),
    Param("FW_AIRSPD_STALL", 7.0, 0.5, 100.0, "m/s", "Stall airspeed"),
    Param("FW_R_LIM", 50.0, 35.0, 65.0, "deg", "Maximum roll angle the position controller commands"),
    Param("FW_P_LIM_MIN", -45.0, -60.0, 0.0, "deg", "Minimum pitch angle the position controller commands"),
    Param("FW_P_LIM_MAX", 45.0, 0.0, 60.0, "deg", "Maximum pitch angle the position controller commands"),
    Param("FW_THR_CRUISE", 0.6, 0.0, 1.0, "", "Throttle at the trim airspeed in level flight"),
    Param("FW_THR_MIN", 0.0, 0.0, 1.0, "", "Minimum throttle in the auto modes"),
    Param("FW_THR_MAX", 1.0, 0.0, 1.0, "", "Maximum throttle in the auto modes"),
    Param(
        "FW_THR_IDLE", 0.0, 0.0, 0.4, "", "Idle throttle: on the ground, and where the flare ramps the throttle to"
    ),
)

ATTITUDE: tuple[Param, ...] = (
    # The attitude loops: rate setpoint = angle error / time constant, within the rate limits.
    Param("FW_R_TC", 0.4, 0.4, 1.0, "s", "Roll time constant: the roll rate setpoint is the roll error over this"),
    Param("FW_P_TC", 0.4, 0.2, 1.0, "s", "Pitch time constant: the pitch rate setpoint is the pitch error over this"),
    Param("FW_R_RMAX", 70.0, 0.0, 90.0, "deg/s", "Maximum roll rate setpoint of the attitude loop"),
    Param("FW_P_RMAX_POS", 60.0, 0.0, 90.0, "deg/s", "Maximum pitch-up rate setpoint of the attitude loop"),
    Param("FW_P_RMAX_NEG", 60.0, 0.0, 90.0, "deg/s", "Maximum pitch-down rate setpoint of the attitude loop"),
    Param("FW_Y_RMAX", 50.0, 0.0, 90.0, "deg/s", "Maximum yaw rate setpoint of the attitude loop"),
    # The rate loops: ω_sp·FF·s + (ω_sp − ω)·P·s² + integrator, s the airspeed scaling.
    Param("FW_RR_P", 0.05, 0.005, 1.0, "1/(rad/s)", "Roll rate proportional gain"),
    Param("FW_RR_I", 0.1, 0.005, 0.2, "1/rad", "Roll rate integrator gain"),
    Param("FW_RR_FF", 0.5, 0.0, 10.0, "1/(rad/s)", "Roll rate feed-forward"),
    Param("FW_RR_IMAX", 0.2, 0.0, 1.0, "", "Roll rate integrator limit (share of the aileron range)"),
    Param("FW_PR_P", 0.08, 0.005, 1.0, "1/(rad/s)", "Pitch rate proportional gain"),
    Param("FW_PR_I", 0.1, 0.005, 0.5, "1/rad", "Pitch rate integrator gain"),
    Param("FW_PR_FF", 0.5, 0.0, 10.0, "1/(rad/s)", "Pitch rate feed-forward"),
    Param("FW_PR_IMAX", 0.4, 0.0, 1.0, "", "Pitch rate integrator limit (share of the elevator range)"),
    Param("FW_YR_P", 0.05, 0.005, 1.0, "1/(rad/s)", "Yaw rate proportional gain"),
    Param("FW_YR_I", 0.1, 0.0, 50.0, "1/rad", "Yaw rate integrator gain"),
    Param("FW_YR_FF", 0.3, 0.0, 10.0, "1/(rad/s)", "Yaw rate feed-forward"),
    Param("FW_YR_IMAX", 0.2, 0.0, 1.0, "", "Yaw rate integrator limit (share of the rudder range)"),
    Param("FW_ARSP_SCALE_EN", True, doc="Scale the rate-loop gains with the airspeed (FW_AIRSPD_TRIM / airspeed)"),
    # Ground steering on the runway (auto takeoff and landing, when the setpoint asks for it).
    Param("FW_W_EN", False, doc="Steer on the ground with the wheel controller when the attitude setpoint asks"),
    Param("FW_WR_P", 0.5, 0.0, 10.0, "1/(rad/s)", "Wheel steering rate proportional gain"),
    Param("FW_WR_I", 0.1, 0.0, 10.0, "1/rad", "Wheel steering rate integrator gain"),
    Param("FW_WR_FF", 0.2, 0.0, 10.0, "1/(rad/s)", "Wheel steering rate feed-forward"),
    Param("FW_WR_IMAX", 0.4, 0.0, 1.0, "", "Wheel steering rate integrator limit"),
    Param("FW_W_RMAX", 30.0, 0.0, 90.0, "deg/s", "Maximum wheel steering (yaw) rate setpoint"),
    # The pilot's modes: Manual (sticks to surfaces), Stabilized (sticks to angles), Acro (sticks to rates).
    Param("FW_MAN_R_MAX", 45.0, 0.0, 90.0, "deg", "Roll angle at full roll stick in Stabilized"),
    Param("FW_MAN_P_MAX", 45.0, 0.0, 90.0, "deg", "Pitch angle at full pitch stick in Stabilized"),
    Param("FW_MAN_R_SC", 1.0, 0.0, 1.0, "", "Manual mode: aileron at full roll stick"),
    # PX4 bounds FW_MAN_R_SC only (0 … 1); its siblings take that bound: the surfaces' command saturates at 1.
    Param("FW_MAN_P_SC", 1.0, 0.0, 1.0, "", "Manual mode: elevator at full pitch stick"),
    Param("FW_MAN_Y_SC", 1.0, 0.0, 1.0, "", "Manual mode: rudder at full yaw stick"),
    Param("FW_ACRO_X_MAX", 90.0, 45.0, 720.0, "deg/s", "Acro: roll rate at full roll stick"),
    Param("FW_ACRO_Y_MAX", 90.0, 45.0, 720.0, "deg/s", "Acro: pitch rate at full pitch stick"),
    Param("FW_ACRO_Z_MAX", 45.0, 10.0, 180.0, "deg/s", "Acro: yaw rate at full yaw stick"),
)

PARAMS: tuple[Param, ...] = SHARED + ATTITUDE
