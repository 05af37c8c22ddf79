"""RotorS' joystick interface (``rotors_joy_interface/src/joy.cpp``): the stick scaling of the RotorS mode.

joy.cpp reads them as the ROS parameters ``max_roll``, ``max_pitch``, ``max_yaw_rate`` and ``max_thrust``; the
defaults are joy.cpp's (10°, 10°, 45°/s, 30 N).
"""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("RJOY_ROLL_MAX", 10.0, 0.0, 60.0, "deg", "RotorS mode: roll at full roll stick (joy.cpp max_roll)"),
    Param("RJOY_PITCH_MAX", 10.0, 0.0, 60.0, "deg", "RotorS mode: pitch at full pitch stick (joy.cpp max_pitch)"),
    Param(
        "RJOY_YAWRATE_MAX", 45.0, 0.0, 360.0, "deg/s", "RotorS mode: yaw rate at full yaw stick (joy.cpp max_yaw_rate)"
    ),
    Param("RJOY_THR_MAX", 30.0, 0.0, 200.0, "N", "RotorS mode: thrust at full throttle (joy.cpp max_thrust)"),
)
