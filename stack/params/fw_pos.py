"""Fixed-wing position control: L1 (``src/lib/l1/``), NPFG (``src/lib/npfg/``), TECS (``src/lib/tecs/``),
runway takeoff (``runway_takeoff_params.c``) and landing (``fw_pos_control_l1_params.c``).

PX4 v1.13's names and defaults, but NPFG's under the names v1.14 gave them (FW_NPFG_*, v1.13: NPFG_*), the
landing's flare as v1.14 has it (``fw_pos_control_params.c``: FW_LND_FL_TIME, FW_LND_FL_SINK, FW_LND_TD_TIME,
FW_LND_FLALT 0.5 m; no FW_LND_HVIRT, FW_LND_TLALT or FW_THR_LND_MAX), and FW_T_HGT_OMEGA from the TECS before
v1.12 (its baro-inertial height filter, used here when the estimator has no vertical velocity)."""

from stack.params.param import ENABLED, Param

L1: tuple[Param, ...] = (
    Param("FW_L1_PERIOD", 20.0, 7.0, 50.0, "s", "L1 period: the closed-loop period of the lateral response"),
    Param("FW_L1_DAMPING", 0.75, 0.6, 0.9, "", "L1 damping"),
    Param(
        "FW_L1_R_SLEW_MAX", 90.0, 0.0, 180.0, "deg/s", "Roll setpoint slew rate limit of the lateral guidance (0 = off)"
    ),
    Param(
        "FW_USE_NPFG",
        0,
        0,
        1,
        "",
        "Lateral guidance: L1 (PX4 v1.13's default) or NPFG",
        values={0: "L1", 1: "NPFG"},
    ),
)

NPFG: tuple[Param, ...] = (
    Param("FW_NPFG_PERIOD", 10.0, 1.0, 100.0, "s", "NPFG period"),
    Param("FW_NPFG_DAMPING", 0.7, 0.1, 1.0, "", "NPFG damping ratio"),
    Param(
        "FW_NPFG_LB_PERIOD",
        1,
        0,
        1,
        "",
        "Lower-bound the NPFG period from the roll time constant (avoids limit cycles; off also disables the "
        "upper bound)",
        values=ENABLED,
    ),
    Param(
        "FW_NPFG_UB_PERIOD",
        1,
        0,
        1,
        "",
        "Upper-bound the NPFG period to keep the track on curved paths in wind",
        values=ENABLED,
    ),
    Param(
        "FW_NPFG_TRACK_KEEP", 1, 0, 1, "", "In excess wind, raise the airspeed to return to the track", values=ENABLED
    ),
    Param(
        "FW_NPFG_EN_MIN_GSP",
        1,
        0,
        1,
        "",
        "Raise the airspeed to keep the minimum forward ground speed FW_GND_SPD_MIN",
        values=ENABLED,
    ),
    Param(
        "FW_NPFG_WIND_REG",
        1,
        0,
        1,
        "",
        "Raise the airspeed in excess wind (off: always the nominal airspeed, and no other increments)",
        values=ENABLED,
    ),
    Param(
        "FW_NPFG_GSP_MAX_TK",
        5.0,
        0.0,
        10.0,
        "m/s",
        "Largest minimum forward ground speed the excess-wind track keeping asks for (at the track error bound)",
    ),
    Param(
        "FW_NPFG_ROLL_TC",
        0.5,
        0.0,
        2.0,
        "s",
        "Roll response time constant, for the lower period bound (0 disables the automatic bounds)",
    ),
    Param(
        "FW_NPFG_SW_DST_MLT",
        0.32,
        0.1,
        1.0,
        "",
        "Waypoint switch distance as a fraction of the track error bound",
    ),
    Param("FW_NPFG_PERIOD_SF", 1.5, 1.0, 10.0, "", "Safety factor on the lower period bound (1 = marginal)"),
    Param("FW_GND_SPD_MIN", 5.0, 0.0, 40.0, "m/s", "Minimum forward ground speed the guidance keeps"),
)

TECS: tuple[Param, ...] = (
    Param("FW_T_CLMB_MAX", 5.0, 1.0, 15.0, "m/s", "Climb rate at FW_THR_MAX and the trim airspeed"),
    Param("FW_T_SINK_MIN", 2.0, 1.0, 5.0, "m/s", "Sink rate at FW_THR_MIN and the trim airspeed"),
    Param("FW_T_SINK_MAX", 5.0, 1.0, 15.0, "m/s", "Largest sink rate the controller commands"),
    # PX4 gives these two a minimum only; the maximum is that of the TECS time constants PX4 had before them,
    # FW_T_TIME_CONST and FW_T_THRO_CONST (1 … 10 s, fw_pos_control_l1_params.c).
    Param("FW_T_ALT_TC", 5.0, 2.0, 10.0, "s", "Altitude error time constant"),
    Param("FW_T_TAS_TC", 5.0, 2.0, 10.0, "s", "True airspeed error time constant"),
    Param("FW_T_THR_DAMP", 0.1, 0.0, 2.0, "", "Throttle damping gain (on the total energy rate error)"),
    Param("FW_T_I_GAIN_THR", 0.3, 0.0, 2.0, "", "Throttle integrator gain (0 = off)"),
    Param("FW_T_I_GAIN_PIT", 0.1, 0.0, 2.0, "", "Pitch integrator gain (0 = off)"),
    Param("FW_T_PTCH_DAMP", 0.1, 0.0, 2.0, "", "Pitch damping gain (on the energy balance rate error)"),
    Param("FW_T_VERT_ACC", 7.0, 1.0, 10.0, "m/s^2", "Largest vertical acceleration the controller uses"),
    Param("FW_T_HRATE_FF", 0.3, 0.0, 1.0, "", "Height rate feed-forward gain"),
    Param(
        "FW_T_SPDWEIGHT",
        1.0,
        0.0,
        2.0,
        "",
        "Speed <-> altitude priority of the pitch loop: 0 altitude only, 1 both, 2 speed only (gliders)",
    ),
    Param("FW_T_SPD_OMEGA", 2.0, 1.0, 10.0, "rad/s", "Crossover frequency of the airspeed complementary filter"),
    Param(
        "FW_T_HGT_OMEGA",
        3.0,
        1.0,
        10.0,
        "rad/s",
        "Crossover frequency of the height complementary filter (used without the estimator's vertical velocity)",
    ),
    Param("FW_T_RLL2THR", 15.0, 0.0, 20.0, "", "Roll -> throttle feed-forward (induced drag in turns)"),
    Param("FW_T_STE_R_TC", 0.4, 0.0, 2.0, "s", "Time constant of the total energy rate error filter"),
    Param("FW_T_TAS_R_TC", 0.2, 0.0, 2.0, "s", "Time constant of the true airspeed rate filter"),
    Param("FW_T_SEB_R_FF", 1.0, 0.5, 3.0, "", "Energy balance rate feed-forward gain"),
    Param("FW_T_CLMB_R_SP", 3.0, 0.5, 15.0, "m/s", "Climb rate the altitude trajectory uses"),
    Param("FW_T_SINK_R_SP", 2.0, 0.5, 15.0, "m/s", "Sink rate the altitude trajectory uses"),
    Param(
        "FW_CLMBOUT_DIFF",
        10.0,
        0.0,
        150.0,
        "m",
        "Climb-out altitude difference: below it a takeoff climbs out at full throttle (0 = no climb-out)",
    ),
)

RUNWAY_TAKEOFF: tuple[Param, ...] = (
    Param(
        "RWTO_HDG",
        0,
        0,
        1,
        "",
        "Heading held on the ground roll",
        values={0: "Airframe heading at the start", 1: "Heading to the takeoff waypoint"},
    ),
    Param("RWTO_NAV_ALT", 5.0, 0.0, 100.0, "m", "Height above the runway where navigation (roll) starts"),
    Param("RWTO_MAX_THR", 1.0, 0.0, 1.0, "", "Throttle of the ground roll"),
    Param("RWTO_PSP", 0.0, -10.0, 20.0, "deg", "Pitch setpoint on the runway, before the takeoff airspeed"),
    Param("RWTO_MAX_PITCH", 20.0, 0.0, 60.0, "deg", "Largest pitch of the takeoff and climb-out (0 = FW_P_LIM_MAX)"),
    Param("RWTO_MAX_ROLL", 25.0, 0.0, 60.0, "deg", "Largest roll of the climb-out below FW_CLMBOUT_DIFF"),
    Param("RWTO_AIRSPD_SCL", 1.3, 0.0, 2.0, "", "Rotate (leave the runway) at this times FW_AIRSPD_MIN"),
    Param("RWTO_RAMP_TIME", 2.0, 1.0, 15.0, "s", "Throttle ramp-up time at the start of the ground roll"),
)

LANDING: tuple[Param, ...] = (
    Param("FW_LND_ANG", 5.0, 1.0, 15.0, "deg", "Landing slope angle"),
    Param(
        "FW_LND_FLALT",
        0.5,
        0.0,
        25.0,
        "m",
        "Flare altitude above the landing point: the flare starts below max(FW_LND_FLALT, FW_LND_FL_TIME * sink rate)",
    ),
    Param(
        "FW_LND_FL_TIME",
        1.0,
        0.1,
        5.0,
        "s",
        "Flare time: times the sink rate, the flare altitude; the time the flare's setpoints and limits ramp over",
    ),
    Param("FW_LND_FL_SINK", 0.25, 0.0, 2.0, "m/s", "Sink rate the flare ends at (TECS on pitch, throttle at idle)"),
    Param(
        "FW_LND_TD_TIME",
        -1.0,
        -1.0,
        5.0,
        "s",
        "Touchdown time after the flare's start (at least FW_LND_FL_TIME): the pitch then goes to RWTO_PSP (-1: off)",
    ),
    Param("FW_LND_HHDIST", 15.0, 0.0, 30.0, "m", "Distance to the landing point where heading hold starts (0 = off)"),
    Param("FW_LND_FL_PMIN", 2.5, 0.0, 15.0, "deg", "Smallest pitch of the flare (nose up)"),
    Param("FW_LND_FL_PMAX", 15.0, 0.0, 45.0, "deg", "Largest pitch of the flare"),
    Param("FW_LND_AIRSPD_SC", 1.3, 1.0, 1.5, "", "Landing airspeed as a multiple of FW_AIRSPD_MIN"),
)

PARAMS: tuple[Param, ...] = L1 + NPFG + TECS + RUNWAY_TAKEOFF + LANDING
