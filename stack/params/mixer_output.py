"""Mixer Output and PWM Outputs (PX4 ``src/lib/mixer_module/params.c``, ``module.yaml``): airmode, the thrust
model and the PWM range."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param(
        "MC_AIRMODE",
        0,
        0,
        2,
        "",
        "Multicopter air-mode: thrust may rise to keep attitude control at low and high throttle (Roll/Pitch/Yaw "
        "also keeps the yaw: thrust may rise for it, but falls for it only within the 15 % yaw margin; no yaw "
        "reset on the arming gesture)",
        values={0: "Disabled", 1: "Roll/Pitch", 2: "Roll/Pitch/Yaw"},
    ),
    Param("THR_MDL_FAC", 0.0, 0.0, 1.0, "", "Thrust model: rel_thrust = f·u² + (1−f)·u (0 linear, 1 quadratic)"),
    Param("PWM_MAIN_DIS", 900, 800, 2200, "us", "PWM while disarmed or for a stopped motor"),
    Param("PWM_MAIN_MIN", 1075, 800, 1400, "us", "PWM for a zero command while armed (motor idle)"),
    Param("PWM_MAIN_MAX", 2000, 1600, 2200, "us", "PWM for a full command"),
)
