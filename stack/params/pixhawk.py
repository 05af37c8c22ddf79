"""The stack's own parameters of the ``pixhawk`` module, which flies a PX4 Pixhawk over MAVLink."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param(
        "PXH_EST_SRC",
        0,
        0,
        1,
        "",
        "Whose estimate flies (a profile then starts no estimator for 1; applies at start)",
        values={0: "The stack's estimators", 1: "The Pixhawk's (EKF2)"},
    ),
    Param(
        "PXH_SP_TYPE",
        0,
        0,
        1,
        "",
        "What the Pixhawk is sent: vehicle_rates_setpoint or vehicle_attitude_setpoint (a profile then starts no "
        "mc_att_control for 1; applies at start)",
        values={0: "Body rates + thrust", 1: "Attitude + thrust"},
    ),
)
