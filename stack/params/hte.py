"""Hover Thrust Estimator (PX4 ``src/modules/mc_hover_thrust_estimator/hover_thrust_estimator_params.c``)."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("HTE_HT_NOISE", 0.0036, 0.0001, 1.0, "1/s", "Hover thrust process noise"),
    Param("HTE_ACC_GATE", 3.0, 1.0, 10.0, "SD", "Acceleration innovation gate"),
    Param("HTE_HT_ERR_INIT", 0.1, 0.0, 1.0, "", "Initial hover thrust uncertainty (1 sigma)"),
    Param("HTE_VXY_THR", 10.0, 1.0, 20.0, "m/s", "Horizontal speed above which measurements are de-weighted"),
    Param("HTE_VZ_THR", 2.0, 1.0, 10.0, "m/s", "Vertical speed above which measurements are de-weighted"),
    Param("HTE_THR_RANGE", 0.2, 0.01, 0.4, "", "Largest deviation of the estimate from MPC_THR_HOVER"),
)
