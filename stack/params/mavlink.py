"""MAVLink (PX4 ``src/modules/mavlink/mavlink_params.c``): the vehicle's MAVLink identity, which the commander
uses to take only the commands addressed to it and the ground-station links to speak as it."""

from stack.params.param import Param

PARAMS: tuple[Param, ...] = (
    Param("MAV_SYS_ID", 1, 1, 250, "", "MAVLink system id of this vehicle"),
    Param("MAV_COMP_ID", 1, 1, 250, "", "MAVLink component id of the autopilot"),
)
