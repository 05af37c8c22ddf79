"""Commander (PX4 ``src/modules/commander/commander_params.c``): arming, disarming, link timeouts and the
failsafe actions, with the stack's COM_EXT_AP."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    Param("COM_DISARM_LAND", 2.0, -1.0, 20.0, "s", "Disarm this long after landing (≤ 0: never)"),
    Param("COM_DISARM_PRFLT", 10.0, -1.0, 20.0, "s", "Disarm this long after arming without taking off (≤ 0: never)"),
    Param(
        "COM_SPOOLUP_TIME",
        1.0,
        0.0,
        30.0,
        "s",
        "Enforced delay between arming and further navigation: thrust stays limited this long after arming",
    ),
    Param("COM_ARM_WO_GPS", 1, 0, 1, "", "Arming without GNSS, in modes that need no position",
          values={0: "Deny arming", 1: "Allow arming"}),
    Param("COM_POS_FS_EPH", 5.0, 0.0, 1000.0, "m", "Horizontal position error above which the position is invalid"),
    Param("COM_DL_LOSS_T", 10, 5, 300, "s", "GCS connection counts as lost after this long without a message"),
    Param("COM_OF_LOSS_T", 1.0, 0.0, 60.0, "s", "Offboard signal counts as lost after this long without one"),
    Param("COM_TAKEOFF_ACT", 0, 0, 1, "", "Action after a takeoff has completed",
          values={0: "Hold", 1: "Mission (if valid)"}),
    Param("COM_FAIL_ACT_T", 5.0, 0.0, 25.0, "s", "Hold this long before a failsafe action (0 = act at once)"),
    Param(
        "NAV_DLL_ACT",
        0,
        0,
        6,
        "",
        "GCS connection loss failsafe action",
        values={0: "Disabled", 1: "Hold mode", 2: "Return mode", 3: "Land mode", 5: "Terminate", 6: "Disarm"},
    ),
    Param(
        "COM_DLL_EXCEPT",
        0,
        0,
        31,
        "",
        "Modes in which a GCS connection loss triggers no failsafe (the stack acts on bits 0 and 1 only)",
        bits={0: "Mission", 1: "Auto modes", 2: "Offboard", 3: "External Mode", 4: "Altitude Cruise"},
    ),
    Param(
        "COM_LOW_BAT_ACT",
        0,
        0,
        3,
        "",
        "Battery failsafe action, at BAT_CRIT_THR and BAT_EMERGEN_THR (1 is older PX4's)",
        values={0: "Warning", 1: "Return mode", 2: "Land mode", 3: "Return at critical level, land at emergency level"},
    ),
    Param(
        "COM_EXT_AP",
        0,
        0,
        1,
        "",
        "The plant is an external autopilot (module pixhawk), which must be connected, armable and armed too "
        "(the stack's own parameter)",
        values=ENABLED,
    ),
)
