"""System (PX4's parameter group of that name): which sensors are fitted, and failure injection."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    Param("SYS_HAS_BARO", 1, 0, 1, "", "A barometer is fitted and required to arm", values=ENABLED),
    Param("SYS_HAS_MAG", 1, 0, 1, "", "Magnetometers fitted and required to arm (PX4 counts them; the stack has one)"),
    Param("SYS_HAS_GPS", 1, 0, 1, "", "A GNSS receiver is fitted", values=ENABLED),
    Param(
        "SYS_HAS_NUM_ASPD",
        1,
        0,
        1,
        "",
        "Airspeed sensors a fixed-wing vehicle has: 1 makes a fresh, valid airspeed a pre-arm check, 0 skips it "
        "(PX4's default is 0; the stack's planes fly with one)",
    ),
    Param(
        "SYS_FAILURE_EN",
        0,
        0,
        1,
        "",
        "Accept failure injection commands (MAV_CMD_INJECT_FAILURE), which the simulator acts on",
        values=ENABLED,
    ),
)
