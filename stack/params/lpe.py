"""Local Position Estimator (PX4 ``src/modules/local_position_estimator/params.c``), with PX4's LPE
defaults. LPE_PN_VZ, LPE_PN_BARO, LPE_PN_GPS_Z, LPE_AIRSPD_VXY and LPE_XY_PUB are the stack's additions;
``stack.estimator.position_kf`` says why."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("LPE_GPS_XY", 1.0, 0.01, 5.0, "m", "Minimum GPS xy standard deviation (the reported eph when larger)"),
    Param("LPE_GPS_Z", 3.0, 0.01, 200.0, "m", "Minimum GPS z standard deviation (the reported epv when larger)"),
    Param("LPE_GPS_VXY", 0.25, 0.01, 2.0, "m/s", "GPS xy velocity standard deviation"),
    Param("LPE_GPS_VZ", 0.25, 0.01, 2.0, "m/s", "GPS z velocity standard deviation"),
    Param("LPE_GPS_DELAY", 0.29, 0.0, 0.4, "s", "GPS delay behind its timestamp_sample"),
    Param("LPE_BAR_Z", 3.0, 0.01, 100.0, "m", "Barometric altitude standard deviation"),
    Param("LPE_ACC_XY", 0.012, 1e-5, 2.0, "m/s^2/sqrt(Hz)", "Accelerometer xy noise density"),
    Param("LPE_ACC_Z", 0.02, 1e-5, 2.0, "m/s^2/sqrt(Hz)", "Accelerometer z noise density"),
    Param("LPE_PN_P", 0.1, 0.0, 1.0, "m/s/sqrt(Hz)", "Position propagation noise density"),
    Param("LPE_PN_V", 0.1, 0.0, 1.0, "m/s^2/sqrt(Hz)", "Velocity propagation noise density"),
    Param("LPE_PN_VZ", 0.1, 0.0, 1.0, "m/s^2/sqrt(Hz)", "Vertical velocity propagation noise density (added)"),
    Param("LPE_PN_B", 1e-3, 0.0, 1.0, "m/s^3/sqrt(Hz)", "Accelerometer bias random walk"),
    Param("LPE_PN_BARO", 0.01, 0.0, 1.0, "m/s/sqrt(Hz)", "Baro offset random walk, GPS height reference (added)"),
    Param("LPE_PN_GPS_Z", 0.13, 0.0, 1.0, "m/s/sqrt(Hz)", "GPS altitude offset random walk, baro reference (added)"),
    Param("LPE_LAND_VXY", 0.05, 0.01, 10.0, "m/s", "Horizontal velocity standard deviation while landed"),
    Param(
        "LPE_AIRSPD_VXY",
        1.0,
        0.0,
        10.0,
        "m/s",
        "Horizontal velocity standard deviation of airspeed plus wind while GPS is lost (0: not fused; added)",
    ),
    Param("LPE_EPH_MAX", 3.0, 1.0, 5.0, "m", "Largest GPS eph to set the origin"),
    Param("LPE_EPV_MAX", 5.0, 1.0, 5.0, "m", "Largest GPS epv to set the origin"),
    Param("LPE_XY_PUB", 2.0, 0.3, 100.0, "m", "eph above which the horizontal position is invalid (added)"),
    Param("LPE_VXY_PUB", 0.3, 0.01, 1.0, "m/s", "Per-axis velocity standard deviation limit for a valid velocity"),
    Param("LPE_Z_PUB", 1.0, 0.3, 5.0, "m", "z standard deviation limit for a valid height and vertical velocity"),
)
