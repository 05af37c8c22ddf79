"""Multicopter Position Control (PX4 ``src/modules/mc_pos_control/multicopter_*_params.c``): the position
controller's gains and limits, the thrust range every thrust-setting module shares, the manual modes'
stick mapping and the auto modes' trajectory."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    # Thrust (multicopter_position_control_params.c, _limits_params.c, _stabilized_mode_params.c)
    Param(
        "MPC_THR_HOVER",
        0.5,
        0.1,
        0.8,
        "norm",
        "Vertical thrust required to hover: the centre throttle stick in Stabilized (MPC_THR_CURVE), where the hover "
        "thrust estimate starts, and the hover thrust of altitude control while no estimate is used (MPC_USE_HTE)",
    ),
    Param("MPC_USE_HTE", True, doc="Use the hover thrust estimate for altitude control instead of MPC_THR_HOVER"),
    Param("MPC_THR_MIN", 0.12, 0.05, 0.5, "norm", "Minimum collective thrust in climb rate controlled modes"),
    Param("MPC_THR_MAX", 1.0, 0.0, 1.0, "norm", "Maximum collective thrust in climb rate controlled modes"),
    Param(
        "MPC_MANTHR_MIN",
        0.08,
        0.0,
        1.0,
        "norm",
        "Minimum collective thrust in Stabilized mode (the lowest throttle stick while flying)",
    ),
    Param(
        "MPC_THR_CURVE",
        0,
        0,
        1,
        "",
        "Thrust curve mapping in Stabilized mode",
        values={0: "Rescale to estimate", 1: "No rescale"},
    ),
    Param("MPC_THR_XY_MARG", 0.3, 0.0, 0.5, "norm", "Horizontal thrust margin kept at vertical saturation"),
    # Gains (multicopter_position_control_gain_params.c)
    Param("MPC_XY_P", 0.95, 0.0, 2.0, "1/s", "Horizontal position gain"),
    Param("MPC_Z_P", 1.0, 0.1, 1.5, "1/s", "Vertical position gain"),
    Param("MPC_XY_VEL_P_ACC", 1.8, 1.2, 5.0, "1/s", "Horizontal velocity P gain"),
    Param("MPC_XY_VEL_I_ACC", 0.4, 0.0, 60.0, "1/s^2", "Horizontal velocity I gain"),
    Param("MPC_XY_VEL_D_ACC", 0.2, 0.1, 2.0, "", "Horizontal velocity D gain"),
    Param("MPC_Z_VEL_P_ACC", 4.0, 2.0, 15.0, "1/s", "Vertical velocity P gain"),
    Param("MPC_Z_VEL_I_ACC", 2.0, 0.2, 3.0, "1/s^2", "Vertical velocity I gain"),
    Param("MPC_Z_VEL_D_ACC", 0.0, 0.0, 2.0, "", "Vertical velocity D gain"),
    Param("MPC_VELD_LP", 5.0, 0.0, 10.0, "Hz", "Low-pass cutoff of the velocity derivative (D term)"),
    # Limits (multicopter_position_control_limits_params.c)
    Param("MPC_XY_VEL_MAX", 12.0, 0.0, 20.0, "m/s", "Maximum horizontal velocity"),
    Param(
        "MPC_Z_VEL_MAX_UP",
        3.0,
        0.5,
        8.0,
        "m/s",
        "Maximum ascent velocity (full stick in Altitude and Position mode; the position controller's limit)",
    ),
    Param(
        "MPC_Z_VEL_MAX_DN",
        1.5,
        0.5,
        4.0,
        "m/s",
        "Maximum descent velocity (full stick in Altitude and Position mode; the position controller's limit)",
    ),
    Param("MPC_TILTMAX_AIR", 45.0, 20.0, 89.0, "deg", "Tilt limit in flight"),
    Param("MPC_TILTMAX_LND", 12.0, 10.0, 89.0, "deg", "Tilt limit on the ground and during takeoff"),
    Param(
        "MPC_ACC_DECOUPLE",
        1,
        0,
        1,
        "",
        "Acceleration to tilt coupling: tilt from the horizontal acceleration only, decoupled from the vertical",
        values=ENABLED,
    ),
    # Takeoff and landing (multicopter_takeoff_land_params.c)
    Param("MPC_TKO_SPEED", 1.5, 1.0, 5.0, "m/s", "Takeoff climb rate"),
    Param("MPC_TKO_RAMP_T", 3.0, 0.0, 5.0, "s", "Smooth takeoff ramp time constant"),
    # PX4 gives the two landing rates a minimum only; their maximum is MPC_Z_VEL_MAX_DN's (4 m/s): the position
    # controller descends no faster than that whatever the landing asks.
    Param("MPC_LAND_SPEED", 0.7, 0.6, 4.0, "m/s", "Landing descend rate (also the blind descent of Descend)"),
    Param("MPC_LAND_CRWL", 0.3, 0.1, 4.0, "m/s", "Land crawl descend rate"),
    Param("MPC_LAND_ALT1", 10.0, 0.0, 122.0, "m", "Height above home below which the descent slows"),
    Param("MPC_LAND_ALT2", 5.0, 0.0, 122.0, "m", "Height above home below which the descent is MPC_LAND_SPEED"),
    # Manual modes (multicopter_stabilized_mode_params.c, _altitude_mode_params.c, _position_mode_params.c)
    Param("MPC_MAN_TILT_MAX", 35.0, 1.0, 70.0, "deg", "Maximal tilt angle in Stabilized and Altitude mode"),
    Param("MPC_MAN_Y_MAX", 150.0, 0.0, 400.0, "deg/s", "Max manual yaw rate for Stabilized, Altitude, Position mode"),
    Param("MPC_VEL_MANUAL", 10.0, 3.0, 20.0, "m/s", "Horizontal speed at full stick in Position mode"),
    Param("MPC_HOLD_DZ", 0.1, 0.0, 1.0, "", "Stick dead zone that engages position or altitude hold"),
    Param("MPC_HOLD_MAX_XY", 0.8, 0.0, 3.0, "m/s", "Horizontal speed below which the position locks"),
    Param("MPC_HOLD_MAX_Z", 0.6, 0.0, 3.0, "m/s", "Vertical speed below which the altitude locks"),
    # Auto modes (multicopter_autonomous_params.c)
    Param("MPC_XY_CRUISE", 5.0, 3.0, 20.0, "m/s", "Horizontal cruise speed in auto modes"),
    Param("MPC_Z_V_AUTO_UP", 3.0, 0.5, 8.0, "m/s", "Climb speed in auto modes"),
    Param("MPC_Z_V_AUTO_DN", 1.5, 0.5, 4.0, "m/s", "Descent speed in auto modes"),
    Param("MPC_ACC_HOR", 3.0, 2.0, 15.0, "m/s^2", "Horizontal acceleration in auto modes"),
    Param("MPC_ACC_UP_MAX", 4.0, 2.0, 15.0, "m/s^2", "Upward acceleration in auto modes"),
    Param("MPC_ACC_DOWN_MAX", 3.0, 2.0, 15.0, "m/s^2", "Downward acceleration in auto modes"),
    Param("MPC_JERK_AUTO", 4.0, 1.0, 80.0, "m/s^3", "Jerk limit in auto modes"),
    Param("MPC_XY_ERR_MAX", 2.0, 0.1, 10.0, "m", "Horizontal lag at which the trajectory waits for the vehicle"),
    Param("MPC_XY_TRAJ_P", 0.5, 0.1, 1.0, "", "Share of MPC_ACC_HOR used to turn at waypoints"),
    Param(
        "MPC_YAW_MODE",
        0,
        0,
        4,
        "",
        "Heading behavior in autonomous modes (4 differs from PX4's 'towards waypoint (yaw first)')",
        values={
            0: "towards waypoint",
            1: "towards home",
            2: "away from home",
            3: "along trajectory",
            4: "hold heading",
        },
    ),
    Param("MPC_YAWRAUTO_MAX", 45.0, 5.0, 360.0, "deg/s", "Heading rate limit in auto modes"),
)
