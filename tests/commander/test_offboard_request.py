"""Which commands ask for Offboard (the glue then checks the offboard signal): infinite parameters are no request,
and never an exception (an exception lost the whole cycle's commands, unanswered)."""

import math

import pytest

from stack.commander.module import CommanderModule
from stack.msg.system import VehicleCommand as CMD


@pytest.mark.parametrize(
    ("params", "wants"),
    [
        ((1.0, 6.0, 0.0), True),
        ((1.0, 6.0, math.nan), True),
        ((1.0, 4.0, 3.0), False),
        ((math.inf, 6.0, 0.0), False),
        ((1.0, math.inf, 0.0), False),
        ((1.0, -math.inf, 0.0), False),
        ((1.0, 6.0, math.inf), True),
        ((math.nan, 6.0, 0.0), False),
    ],
)
def test_do_set_mode_asks_for_offboard_only_with_finite_parameters(params, wants):
    p1, p2, p3 = params
    cmd = CMD(command=CMD.VEHICLE_CMD_DO_SET_MODE, param1=p1, param2=p2, param3=p3)
    assert CommanderModule._wants_offboard(cmd) is wants
