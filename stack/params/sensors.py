"""Sensors (PX4 ``src/modules/sensors/vehicle_angular_velocity/imu_gyro_parameters.c``): the body-rate filters."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("IMU_GYRO_CUTOFF", 40.0, 0.0, 1000.0, "Hz", "Body-rate low-pass cutoff (0 = off)"),
    Param("IMU_DGYRO_CUTOFF", 20.0, 0.0, 1000.0, "Hz", "Angular-acceleration low-pass cutoff (0 = off)"),
)
