"""Commands from a ground station: COMMAND_LONG, COMMAND_INT and SET_MODE → ``vehicle_command``, and the
COMMAND_ACK that answers each, addressed to its sender (I/O-free).

As PX4's ``MavlinkReceiver`` (``src/modules/mavlink/mavlink_receiver.cpp``): a command addressed to this system
(or to all, 0) and to the autopilot component (or all) becomes a ``vehicle_command`` with its sender as the
source, and the ``vehicle_command_ack`` the commander publishes for that source is sent back as COMMAND_ACK.
Commands the stack does not carry out are answered UNSUPPORTED at once, never forwarded. NaN parameters mean
"not given" all the way through. Where PX4 reads a parameter differently from the MAVLink text, the stack's
commander (which follows the text) is given what PX4 would have understood:

* DO_REPOSITION param4 (yaw) is radians for PX4's navigator (``navigator_main.cpp``) and for MAVSDK's
  ``goto_location``; the commander takes degrees.
* NAV_TAKEOFF param2 is unused in MAVLink; the commander's own extension there (altitude above home) is not
  reachable from a link.

COMMAND_INT carries latitude/longitude as degE7 integers (INT32_MAX: not given) and the altitude in its frame:
AMSL for GLOBAL(_INT), above home for GLOBAL_RELATIVE_ALT(_INT) (converted with home's altitude); other frames are
refused for commands that take a position.

SET_MODE (#11, no acknowledgement) becomes DO_SET_MODE with PX4's main and sub mode, as PX4 does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.msg.system import HomePosition, VehicleCommand, VehicleCommandAck, command_label

CMD = VehicleCommand
INT32_MAX = 0x7FFF_FFFF
MAV_COMP_ID_ALL = 0
POSITION_COMMANDS = frozenset(
    {
        CMD.VEHICLE_CMD_NAV_LOITER_UNLIM,
        CMD.VEHICLE_CMD_NAV_LAND,
        CMD.VEHICLE_CMD_NAV_TAKEOFF,
        CMD.VEHICLE_CMD_DO_REPOSITION,
    }
)
"""Commands whose param5/6/7 are latitude, longitude and altitude."""
AMSL_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL, mavlink2.MAV_FRAME_GLOBAL_INT})
RELATIVE_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT, mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})


@dataclass(frozen=True)
class Refusal:
    """A command answered here, without reaching the commander."""

    result: int
    reason: str = ""
    param: int = 0


def addressed_to(target_system: int, target_component: int, own: tuple[int, int]) -> bool:
    """Whether a command is for this vehicle's autopilot (0 is a broadcast)."""
    return target_system in (0, own[0]) and target_component in (MAV_COMP_ID_ALL, own[1])


def _vehicle_command(
    command: int, params: list[float], source: tuple[int, int], own: tuple[int, int], confirmation: int = 0
) -> VehicleCommand:
    return CMD(
        command=command,
        param1=params[0],
        param2=params[1],
        param3=params[2],
        param4=params[3],
        param5=params[4],
        param6=params[5],
        param7=params[6],
        target_system=own[0],
        target_component=own[1],
        source_system=source[0],
        source_component=source[1],
        confirmation=confirmation,
        from_external=True,
    )


def _px4_meaning(command: int, params: list[float]) -> list[float]:
    if command == CMD.VEHICLE_CMD_DO_REPOSITION and math.isfinite(params[3]):
        params[3] = math.degrees(params[3])
    elif command == CMD.VEHICLE_CMD_NAV_TAKEOFF:
        params[1] = math.nan
    return params


def from_command_long(
    msg: mavlink2.MAVLink_command_long_message, source: tuple[int, int], own: tuple[int, int], supported: frozenset[int]
) -> VehicleCommand | Refusal:
    if msg.command not in supported:
        return Refusal(mavlink2.MAV_RESULT_UNSUPPORTED)
    params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7]
    return _vehicle_command(msg.command, _px4_meaning(msg.command, params), source, own, msg.confirmation)


def _degrees(e7: int) -> float:
    return math.nan if e7 == INT32_MAX else e7 / 1e7


def from_command_int(
    msg: mavlink2.MAVLink_command_int_message,
    source: tuple[int, int],
    own: tuple[int, int],
    supported: frozenset[int],
    home_alt: float,
) -> VehicleCommand | Refusal:
    """``home_alt``: home's altitude AMSL [m] (NaN when unknown), for altitudes given above home."""
    if msg.command not in supported:
        return Refusal(mavlink2.MAV_RESULT_UNSUPPORTED)
    z = msg.z
    if msg.command in POSITION_COMMANDS:
        if msg.frame in RELATIVE_FRAMES:
            if math.isfinite(z) and not math.isfinite(home_alt):
                return Refusal(
                    mavlink2.MAV_RESULT_DENIED, "Command refused: an altitude above home, but no home yet", 7
                )
            z = z + home_alt if math.isfinite(z) else z
        elif msg.frame not in AMSL_FRAMES:
            return Refusal(
                mavlink2.MAV_RESULT_DENIED,
                f"Command {command_label(msg.command)} refused: frame {msg.frame} is not supported "
                "(use a global frame)",
            )
    params = [msg.param1, msg.param2, msg.param3, msg.param4, _degrees(msg.x), _degrees(msg.y), z]
    return _vehicle_command(msg.command, _px4_meaning(msg.command, params), source, own)


def from_command(
    msg: mavlink2.MAVLink_command_long_message | mavlink2.MAVLink_command_int_message,
    source: tuple[int, int],
    own: tuple[int, int],
    supported: frozenset[int],
    home: HomePosition | None,
) -> VehicleCommand | Refusal:
    """COMMAND_LONG or COMMAND_INT; a COMMAND_INT's altitudes above home are placed with ``home``'s altitude while
    it is valid."""
    if msg.get_type() == "COMMAND_INT":
        home_alt = home.alt if home is not None and home.valid_alt else math.nan
        return from_command_int(msg, source, own, supported, home_alt)
    return from_command_long(msg, source, own, supported)


def from_set_mode(
    msg: mavlink2.MAVLink_set_mode_message, source: tuple[int, int], own: tuple[int, int]
) -> VehicleCommand:
    """SET_MODE → DO_SET_MODE (param1 base mode, param2/3 PX4's main/sub mode), as PX4's receiver does."""
    main, sub = px4_modes.main_sub(msg.custom_mode)
    params = [float(msg.base_mode), float(main), float(sub), math.nan, math.nan, math.nan, math.nan]
    return _vehicle_command(CMD.VEHICLE_CMD_DO_SET_MODE, params, source, own)


def command_ack(
    command: int, result: int, to: tuple[int, int], result_param2: int = 0
) -> mavlink2.MAVLink_command_ack_message:
    return mavlink2.MAVLink_command_ack_message(command, result, 0, result_param2, to[0], to[1])


class PendingCommands:
    """Commands forwarded to the commander and not answered yet, by (command, sender), oldest first. A repeat of a
    pending command with the same parameters (MAVSDK resends after 0.5 s without an answer) is not forwarded
    again: the answer to the first answers it; the same command with other parameters (arm, then disarm) is. After
    ``timeout_us`` without an answer a command is answered FAILED."""

    def __init__(self, timeout_us: int) -> None:
        self.timeout_us = timeout_us
        self._pending: dict[tuple[int, int, int], list[tuple[int, tuple[float, ...]]]] = {}

    def __len__(self) -> int:
        return sum(len(waiting) for waiting in self._pending.values())

    def add(self, cmd: VehicleCommand, now_us: int) -> bool:
        """Note a command about to be forwarded; False if the same one is already waiting for its answer."""
        params = (cmd.param1, cmd.param2, cmd.param3, cmd.param4, cmd.param5, cmd.param6, cmd.param7)
        waiting = self._pending.setdefault((cmd.command, cmd.source_system, cmd.source_component), [])
        if any(_same(params, other) for _, other in waiting):
            return False
        waiting.append((now_us, params))
        return True

    def answer(self, ack: VehicleCommandAck) -> mavlink2.MAVLink_command_ack_message | None:
        """The COMMAND_ACK for a commander's acknowledgement of a command forwarded from this link, else None."""
        key = (ack.command, ack.target_system, ack.target_component)
        waiting = self._pending.get(key)
        if not waiting:
            return None
        waiting.pop(0)
        if not waiting:
            del self._pending[key]
        return command_ack(ack.command, ack.result, (ack.target_system, ack.target_component), ack.result_param2)

    def expired(self, now_us: int) -> list[mavlink2.MAVLink_command_ack_message]:
        """FAILED for the commands that have waited too long."""
        late = []
        for key, waiting in list(self._pending.items()):
            while waiting and now_us - waiting[0][0] > self.timeout_us:
                waiting.pop(0)
                late.append(key)
            if not waiting:
                del self._pending[key]
        return [
            command_ack(command, VehicleCommandAck.VEHICLE_CMD_RESULT_FAILED, (sys, comp))
            for command, sys, comp in late
        ]


def _same(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """Parameters equal, NaN equal to NaN ("not given" both times)."""
    return all(x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a, b, strict=True))
