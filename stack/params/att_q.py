"""Attitude Q estimator (PX4 ``src/modules/attitude_estimator_q/attitude_estimator_q_params.c``)."""

from stack.params.param import ENABLED, Param

PARAMS: tuple[Param, ...] = (
    Param("ATT_W_ACC", 0.2, 0.0, 1.0, "1/s", "Accelerometer (tilt) correction weight"),
    Param("ATT_W_MAG", 0.1, 0.0, 1.0, "1/s", "Magnetometer (heading) correction weight"),
    Param("ATT_W_GYRO_BIAS", 0.1, 0.0, 1.0, "1/s", "Gyro bias learning weight"),
    Param("ATT_BIAS_MAX", 0.05, 0.0, 2.0, "rad/s", "Gyro bias limit"),
    Param("ATT_MAG_DECL", 0.0, -180.0, 180.0, "deg", "Magnetic declination, east positive"),
    Param(
        "ATT_ACC_COMP",
        0,
        0,
        1,
        "",
        "Compensate the accelerometer with the velocity-derived acceleration",
        values=ENABLED,
    ),
    Param("ATT_ACC_COMP_LP", 1.0, 0.0, 10.0, "Hz", "Low-pass cutoff of the velocity-derived acceleration (0 = off)"),
)
