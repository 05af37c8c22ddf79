"""Battery Calibration (PX4 ``src/lib/battery/module.yaml``): the pack and the warning thresholds."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("BAT1_N_CELLS", 4, 1, 16, "", "Number of cells in series", values={n: f"{n}S Battery" for n in range(1, 17)}),
    Param("BAT1_CAPACITY", 5000.0, 1.0, 100000.0, "mAh", "Pack capacity"),
    Param("BAT1_V_EMPTY", 3.6, 2.5, 4.5, "V", "Cell voltage when empty (open circuit)"),
    Param("BAT1_V_CHARGED", 4.05, 3.0, 5.0, "V", "Cell voltage when full (open circuit)"),
    Param("BAT_LOW_THR", 0.15, 0.12, 0.5, "norm", "Remaining charge below which the warning is LOW"),
    Param("BAT_CRIT_THR", 0.07, 0.05, 0.5, "norm", "Remaining charge below which the warning is CRITICAL"),
    Param("BAT_EMERGEN_THR", 0.05, 0.03, 0.5, "norm", "Remaining charge below which the warning is EMERGENCY"),
)
