"""EKF2 (PX4 ``src/modules/ekf2/params_*.yaml``): the names the stack's position filter takes from EKF2, for
what LPE has no parameter for; ``stack.estimator.position_kf`` says why."""

from stack.params.param import Param

HGT_REF_BARO = 0
HGT_REF_GPS = 1

PARAMS: tuple[Param, ...] = (
    Param(
        "EKF2_HGT_REF",
        HGT_REF_BARO,
        HGT_REF_BARO,
        HGT_REF_GPS,
        "",
        "Height reference (applies at the filter's next reset; PX4's 2 range sensor and 3 vision are not offered)",
        values={HGT_REF_BARO: "Barometric pressure", HGT_REF_GPS: "GPS"},
    ),
    Param("EKF2_GPS_P_GATE", 5.0, 1.0, 10.0, "SD", "GPS position innovation gate"),
    Param("EKF2_GPS_V_GATE", 5.0, 1.0, 10.0, "SD", "GPS velocity innovation gate"),
    Param("EKF2_BARO_GATE", 5.0, 1.0, 10.0, "SD", "Barometer innovation gate"),
    Param("EKF2_TAS_GATE", 5.0, 1.0, 10.0, "SD", "Airspeed (dead-reckoning velocity) innovation gate"),
    Param("EKF2_ABL_LIM", 0.4, 0.0, 0.8, "m/s^2", "Accelerometer bias limit"),
    Param("EKF2_ABIAS_INIT", 0.2, 0.0, 0.5, "m/s^2", "Initial accelerometer bias standard deviation"),
)
