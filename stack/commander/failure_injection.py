"""SYS_FAILURE_EN: whether injected failures (MAV_CMD_INJECT_FAILURE) are accepted.

Shared by the commander, which denies the command while it is 0, and the simulator, which only acts
on an injected failure while it is 1.
"""

from stack.runtime.params import Param

FAILURE_INJECTION_PARAM = Param(
    "SYS_FAILURE_EN", 0, 0, 1, "", "Accept failure injection commands (simulation)", choices=(0, 1)
)
