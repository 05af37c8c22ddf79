"""The stack's parameters as a :class:`~stack.mavlink.params.ParamSource`: the parameter client every tool uses.

:mod:`stack.params.client` lists each parameter once with the modules that read it, and sets it in all of them or
in none, as ``stack param`` does. MAVLink knows INT32 and REAL32 only: booleans and integers go as INT32.
"""

from __future__ import annotations

import zenoh

from stack.mavlink.params import ParamNumber
from stack.params import client
from stack.params.param import MAV_PARAM_TYPE_INT32, ParamError


class BusParamSource:
    def __init__(self, session: zenoh.Session, vehicle: str, timeout_s: float = client.TIMEOUT_S) -> None:
        self.session = session
        self.vehicle = vehicle
        self.timeout_s = timeout_s

    def list(self) -> list[tuple[str, ParamNumber, bool]]:
        entries = []
        for p in client.list_params(self.session, self.vehicle, self.timeout_s):
            is_int = p.param.mav_type == MAV_PARAM_TYPE_INT32
            entries.append((p.name, int(p.value) if is_int else float(p.value), is_int))
        return entries

    def set(self, name: str, value: ParamNumber) -> ParamNumber:
        try:
            new = client.set_param(self.session, self.vehicle, name, value, self.timeout_s).new
        except ParamError as e:
            # The ground station shows the reason after the parameter's name already.
            raise ParamError(str(e).removeprefix(f"{name}: ")) from None
        return int(new) if isinstance(new, bool | int) else float(new)
