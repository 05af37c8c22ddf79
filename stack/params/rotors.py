"""RotorS (ethz-asl/rotors_simulator): the joystick interface of the RotorS mode and the gains of the
roll-pitch-yawrate-thrust controller.

``rotors_joy_interface/src/joy.cpp`` reads its stick scaling as the ROS parameters ``max_roll``, ``max_pitch``,
``max_yaw_rate`` and ``max_thrust``; the defaults are joy.cpp's (10°, 10°, 45°/s, 30 N).

``rotors_control`` reads the controller's ``attitude_gain`` and ``angular_rate_gain`` (x, y, z about body FLU)
from ``rotors_gazebo/resource/roll_pitch_yawrate_thrust_controller_<mav>.yaml``; the defaults are the
Firefly's, RotorS' default vehicle. Each gain is a torque per unit error [N·m/rad, N·m/(rad/s)]: the
controller divides it by the inertia to make an angular acceleration, and the allocation multiplies it back.
"""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("RJOY_ROLL_MAX", 10.0, 0.0, 60.0, "deg", "RotorS mode: roll at full roll stick (joy.cpp max_roll)"),
    Param("RJOY_PITCH_MAX", 10.0, 0.0, 60.0, "deg", "RotorS mode: pitch at full pitch stick (joy.cpp max_pitch)"),
    Param(
        "RJOY_YAWRATE_MAX", 45.0, 0.0, 360.0, "deg/s", "RotorS mode: yaw rate at full yaw stick (joy.cpp max_yaw_rate)"
    ),
    Param("RJOY_THR_MAX", 30.0, 0.0, 200.0, "N", "RotorS mode: thrust at full throttle (joy.cpp max_thrust)"),
    Param("RPYT_ATT_GAIN_X", 3.0, 0.0, 100.0, "N·m/rad", "RotorS controller: roll attitude gain (attitude_gain x)"),
    Param("RPYT_ATT_GAIN_Y", 3.0, 0.0, 100.0, "N·m/rad", "RotorS controller: pitch attitude gain (attitude_gain y)"),
    Param("RPYT_ATT_GAIN_Z", 0.035, 0.0, 100.0, "N·m/rad", "RotorS controller: yaw attitude gain (attitude_gain z)"),
    Param(
        "RPYT_RATE_GAIN_X", 0.52, 0.0, 10.0, "N·m·s/rad", "RotorS controller: roll rate gain (angular_rate_gain x)"
    ),
    Param(
        "RPYT_RATE_GAIN_Y", 0.52, 0.0, 10.0, "N·m·s/rad", "RotorS controller: pitch rate gain (angular_rate_gain y)"
    ),
    Param(
        "RPYT_RATE_GAIN_Z", 0.025, 0.0, 10.0, "N·m·s/rad", "RotorS controller: yaw rate gain (angular_rate_gain z)"
    ),
)
