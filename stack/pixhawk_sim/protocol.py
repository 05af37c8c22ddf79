"""The simulated Pixhawk's MAVLink behaviour, as PX4's ``mavlink`` module and commander answer a companion.

:class:`Px4Protocol` is free of I/O: it takes received messages and the time, and hands what to send to a
``send`` callable (the link layer's ``send``). It provides:

* the HEARTBEAT content (the link sends it at 1 Hz): MAV_TYPE from the rotor count, MAV_AUTOPILOT_PX4, PX4's
  base mode flags and custom mode, system status STANDBY, ACTIVE, CRITICAL in a failsafe or FLIGHT_TERMINATION;
* the streams at their intervals (:class:`~stack.mavlink.streams.StreamScheduler` with :data:`STREAM_RATES_HZ`),
  and the commander's notices as STATUSTEXT (split into 50-character chunks with an id, as MAVLink 2 allows);
* a COMMAND_ACK for every COMMAND_LONG and COMMAND_INT addressed to it (target 0 or its own ids):
  COMPONENT_ARM_DISARM (400), DO_SET_MODE (176) with PX4 custom modes, NAV_LAND (21) and NAV_LOITER_UNLIM (17) as
  mode changes, SET_MESSAGE_INTERVAL (511), GET_MESSAGE_INTERVAL (510), REQUEST_MESSAGE (512),
  REQUEST_AUTOPILOT_CAPABILITIES (520); any other command is UNSUPPORTED. A requested message goes out before
  the ACK, as in PX4. SET_MESSAGE_INTERVAL and REQUEST_MESSAGE with a response target (param7) other than 0
  FAILED, as PX4's ``MavlinkReceiver::set_message_interval`` refuses it.
* SET_ATTITUDE_TARGET addressed to it: the Offboard setpoint stream (:mod:`~stack.pixhawk_sim.offboard`).

Not modelled: parameters, missions, SET_POSITION_TARGET_* setpoints, MANUAL_CONTROL.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pymavlink.dialects.v20 import common as mavlink

from stack.commander.command_checks import arm_action, arm_forced
from stack.mavlink import commands, px4_modes
from stack.mavlink.px4_modes import Px4Mode
from stack.mavlink.statustext import StatustextSender
from stack.mavlink.streams import ONBOARD_RATES_HZ, StreamScheduler
from stack.msg.system import VehicleCommand
from stack.pixhawk_sim.commander import Verdict
from stack.pixhawk_sim.modes import base_mode_flags
from stack.pixhawk_sim.telemetry import Message, Telemetry
from stack.pixhawk_sim.vehicle import SimulatedPixhawk

MAV_TYPES = {4: mavlink.MAV_TYPE_QUADROTOR, 6: mavlink.MAV_TYPE_HEXAROTOR, 8: mavlink.MAV_TYPE_OCTOROTOR}
"""MAV_TYPE by rotor count (PX4's MAV_TYPE of the multicopter airframes)."""
STREAM_RATES_HZ: dict[int, float] = {**ONBOARD_RATES_HZ, mavlink.MAVLINK_MSG_ID_SIM_STATE: 50.0}
"""PX4's ONBOARD-mode rates, and SIM_STATE: not a PX4 stream; the simulated Pixhawk sends its truth at 50 Hz so a
scenario can be judged."""
MIN_STREAM_INTERVAL_US = 1
"""SET_MESSAGE_INTERVAL may ask for any rate; faster than the 250 Hz loop means every loop."""


def stream_scheduler() -> StreamScheduler:
    """The simulated Pixhawk's streams (GPS_RAW_INT is sent on every new GPS sample, as PX4's unlimited rate)."""
    return StreamScheduler(STREAM_RATES_HZ, MIN_STREAM_INTERVAL_US)


class Px4Protocol:
    """See the module docstring."""

    def __init__(
        self,
        vehicle: SimulatedPixhawk,
        send: Callable[[Message], None],
        system_id: int = 1,
        component_id: int = mavlink.MAV_COMP_ID_AUTOPILOT1,
        telemetry: Telemetry | None = None,
    ) -> None:
        self.vehicle = vehicle
        self.send = send
        self.system_id = system_id
        self.component_id = component_id
        self.telemetry = telemetry or Telemetry(vehicle)
        self.streams = stream_scheduler()
        self.mav_type = MAV_TYPES.get(vehicle.sim.model.rotor_count, mavlink.MAV_TYPE_GENERIC)
        self.commands = 0
        self.setpoints = 0
        self._texts = StatustextSender(max_chunks=None, one_full_message=True)
        self._handlers: dict[int, Callable[[tuple[float, ...]], Verdict]] = {
            mavlink.MAV_CMD_COMPONENT_ARM_DISARM: self._arm_disarm,
            mavlink.MAV_CMD_DO_SET_MODE: self._set_mode,
            mavlink.MAV_CMD_NAV_LAND: lambda p: self.vehicle.set_mode(Px4Mode.AUTO_LAND),
            mavlink.MAV_CMD_NAV_LOITER_UNLIM: lambda p: self.vehicle.set_mode(Px4Mode.AUTO_LOITER),
            mavlink.MAV_CMD_SET_MESSAGE_INTERVAL: self._set_message_interval,
            mavlink.MAV_CMD_GET_MESSAGE_INTERVAL: self._get_message_interval,
            mavlink.MAV_CMD_REQUEST_MESSAGE: self._request_message,
            mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: self._request_capabilities,
        }

    # ------------------------------------------------------------------ outbound

    def heartbeat(self) -> dict:
        """HEARTBEAT fields for the link layer (PX4 ``streams/HEARTBEAT.hpp``)."""
        v = self.vehicle
        c = v.commander
        if c.terminated:
            status = mavlink.MAV_STATE_FLIGHT_TERMINATION
        elif c.armed:
            status = mavlink.MAV_STATE_CRITICAL if c.failsafe else mavlink.MAV_STATE_ACTIVE
        else:
            status = mavlink.MAV_STATE_STANDBY
        return {
            "type": self.mav_type,
            "autopilot": mavlink.MAV_AUTOPILOT_PX4,
            "base_mode": base_mode_flags(c.mode, c.armed, v.flying_attitude),
            "custom_mode": px4_modes.encode(c.mode),
            "system_status": status,
        }

    def publish(self) -> None:
        """Send the streams due now and the commander's notices."""
        self.publish_notices()
        telemetry = self.telemetry
        for msg_id in self.streams.due(self.vehicle.time_us):
            msg = telemetry.build(msg_id)
            if msg is not None:
                self.send(msg)

    def statustext(self, severity: int, text: str) -> None:
        for msg in self._texts.messages(severity, text):
            self.send(msg)

    # ------------------------------------------------------------------ inbound

    def handle(self, msg: Message) -> None:
        msg_id = msg.get_msgId()
        if msg_id == mavlink.MAVLINK_MSG_ID_SET_ATTITUDE_TARGET:
            if self._addressed(msg.target_system, msg.target_component):
                self.setpoints += 1
                self.vehicle.attitude_target(msg)
        elif msg_id == mavlink.MAVLINK_MSG_ID_COMMAND_LONG:
            params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
            self._command(msg, params)
        elif msg_id == mavlink.MAVLINK_MSG_ID_COMMAND_INT:
            params = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
            self._command(msg, params)

    def _addressed(self, system: int, component: int) -> bool:
        return commands.addressed_to(system, component, (self.system_id, self.component_id))

    def _command(self, msg: Message, params: tuple[float, ...]) -> None:
        if not self._addressed(msg.target_system, msg.target_component):
            return
        self.commands += 1
        handler = self._handlers.get(msg.command)
        verdict = handler(params) if handler is not None else Verdict(mavlink.MAV_RESULT_UNSUPPORTED)
        self.publish_notices()
        self.send(commands.command_ack(msg.command, verdict.result, (msg.get_srcSystem(), msg.get_srcComponent())))

    def publish_notices(self) -> None:
        for notice in self.vehicle.commander.take_notices():
            self.statustext(notice.severity, notice.text)

    def _arm_disarm(self, p: tuple[float, ...]) -> Verdict:
        action = arm_action(p[0])
        if action is None:
            return Verdict(mavlink.MAV_RESULT_DENIED, f"unsupported ARM_DISARM param1 {p[0]}")
        return self.vehicle.arm_disarm(action == VehicleCommand.ARMING_ACTION_ARM, arm_forced(p[1]))

    def _set_mode(self, p: tuple[float, ...]) -> Verdict:
        base = int(p[0]) if math.isfinite(p[0]) else 0
        if not base & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED or not math.isfinite(p[1]):
            return Verdict(mavlink.MAV_RESULT_DENIED, "only PX4 custom modes are simulated")
        sub = int(p[2]) if math.isfinite(p[2]) else 0
        return self.vehicle.set_mode(px4_modes.decode((int(p[1]) << 16) | (sub << 24)))

    def _set_message_interval(self, p: tuple[float, ...]) -> Verdict:
        if not (math.isfinite(p[0]) and math.isfinite(p[1])) or _response_target(p[6]):
            return Verdict(mavlink.MAV_RESULT_FAILED)
        ok = self.streams.set_interval(round(p[0]), p[1])
        return Verdict(mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_FAILED)

    def _get_message_interval(self, p: tuple[float, ...]) -> Verdict:
        if not math.isfinite(p[0]):
            return Verdict(mavlink.MAV_RESULT_FAILED)
        msg_id = round(p[0])
        self.send(mavlink.MAVLink_message_interval_message(msg_id, self.streams.interval_us(msg_id)))
        return Verdict(mavlink.MAV_RESULT_ACCEPTED)

    def _request_message(self, p: tuple[float, ...]) -> Verdict:
        if not math.isfinite(p[0]) or _response_target(p[6]):
            return Verdict(mavlink.MAV_RESULT_FAILED)
        msg_id = round(p[0])
        if msg_id == mavlink.MAVLINK_MSG_ID_MESSAGE_INTERVAL:
            return self._get_message_interval(p[1:])
        msg = self.telemetry.request(msg_id)
        if msg is None:
            return Verdict(mavlink.MAV_RESULT_FAILED)
        self.send(msg)
        return Verdict(mavlink.MAV_RESULT_ACCEPTED)

    def _request_capabilities(self, p: tuple[float, ...]) -> Verdict:
        if not (math.isfinite(p[0]) and round(p[0]) == 1):
            return Verdict(mavlink.MAV_RESULT_DENIED)
        self.send(self.telemetry.autopilot_version())
        return Verdict(mavlink.MAV_RESULT_ACCEPTED)


def _response_target(param7: float) -> bool:
    """Whether param7 asks for a response target other than the default (0), which PX4 refuses."""
    return math.isfinite(param7) and round(param7) != 0
