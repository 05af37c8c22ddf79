"""MAVLink (PX4 ``src/modules/mavlink/mavlink_params.c``): the vehicle's MAVLink identity, which the commander
uses to take only the commands addressed to it and the ground-station links to speak as it, and its type,
from which the commander also knows whether it flies a rotary-wing or a fixed-wing vehicle."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("MAV_SYS_ID", 1, 1, 250, "", "MAVLink system id of this vehicle"),
    Param("MAV_COMP_ID", 1, 1, 250, "", "MAVLink component id of the autopilot"),
    Param(
        "MAV_TYPE",
        2,
        1,
        15,
        "",
        "The vehicle's type (MAVLink MAV_TYPE, in the HEARTBEAT): fixed wing or a rotary-wing type; changes "
        "take effect while disarmed",
        values={
            1: "Fixed wing aircraft",
            2: "Quadrotor",
            3: "Coaxial helicopter",
            4: "Normal helicopter with tail rotor",
            13: "Hexarotor",
            14: "Octorotor",
            15: "Tricopter",
        },
    ),
)
