"""Auto-disarm (I/O-free): COM_DISARM_LAND seconds after landing once the vehicle has taken off, COM_DISARM_PRFLT
seconds after arming without taking off; 0 (or less) turns either off.

PX4 ``src/modules/commander/Commander.cpp``, ``Commander::checkForAutoDisarm``: one hysteresis (false → true after
the hold time) fed "landed" once airborne, or "true" before takeoff. Written once for the stack's commander and the
simulated Pixhawk's.
"""

from __future__ import annotations

from stack.commander.hysteresis import Hysteresis
from stack.params.binding import ParamSet


class AutoDisarmParams(ParamSet):
    com_disarm_land: float
    com_disarm_prflt: float


class AutoDisarm:
    __slots__ = ("_hysteresis", "land_us", "preflight_us")

    def __init__(self) -> None:
        self._hysteresis = Hysteresis(False)
        self.land_us = 0
        self.preflight_us = 0

    def set_params(self, p: AutoDisarmParams) -> None:
        self.land_us = round(p.com_disarm_land * 1e6)
        self.preflight_us = round(p.com_disarm_prflt * 1e6)

    def reset(self) -> None:
        """Armed or disarmed: nothing pending."""
        self._hysteresis.force(False)

    def update(self, now_us: int, landed: bool, have_taken_off: bool, hold_landed: bool = False) -> bool:
        """Whether an armed vehicle is to disarm now. ``hold_landed``: no disarm after landing for now (the stack's
        commander holds it while a mission is not finished)."""
        hysteresis = self._hysteresis
        if self.land_us > 0 and have_taken_off and not hold_landed:
            hysteresis.set_hysteresis_time_from(False, self.land_us)
            hysteresis.set_state_and_update(landed, now_us)
        elif self.preflight_us > 0 and not have_taken_off:
            hysteresis.set_hysteresis_time_from(False, self.preflight_us)
            hysteresis.set_state_and_update(True, now_us)
        return hysteresis.state
