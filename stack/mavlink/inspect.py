"""``stack mavlink inspect``: what a user checks first on any MAVLink autopilot.

:class:`Inspection` turns the messages seen into a summary without any I/O; :func:`inspect_endpoint` is the connect
loop around it: a GCS-like heartbeat, AUTOPILOT_VERSION asked with MAV_CMD_REQUEST_MESSAGE (and, if that is
unsupported, with the older MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, as MAVSDK does).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import msgspec
from pymavlink.dialects.v20 import common as mavlink2

from stack.mavlink import px4_modes
from stack.mavlink.link import LinkCounters, MavlinkLink, monotonic_us

INSPECTOR_SYSTEM_ID = 255  # a ground station's ids, as QGroundControl's
INSPECTOR_COMPONENT_ID = mavlink2.MAV_COMP_ID_MISSIONPLANNER
VERSION_REQUEST_PERIOD_US = 1_000_000


class NoHeartbeat(Exception):
    """Nothing that sends a heartbeat answered on the endpoint."""


@dataclass
class _MessageTraffic:
    msg_id: int
    count: int = 0
    first_us: int = 0
    last_us: int = 0

    def rate_hz(self, window_us: int) -> float:
        if self.count >= 2 and self.last_us > self.first_us:
            return (self.count - 1) * 1e6 / (self.last_us - self.first_us)
        return self.count * 1e6 / window_us if window_us > 0 else 0.0


@dataclass
class Inspection:
    traffic: dict[tuple[tuple[int, int], str], _MessageTraffic] = field(default_factory=dict)
    heartbeats: dict[tuple[int, int], mavlink2.MAVLink_heartbeat_message] = field(default_factory=dict)
    autopilot: tuple[int, int] | None = None
    version: mavlink2.MAVLink_autopilot_version_message | None = None
    version_unsupported: bool = False
    mavlink_versions: set[int] = field(default_factory=set)

    def observe(self, msg: mavlink2.MAVLink_message, now_us: int) -> None:
        name = msg.get_type()
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        traffic = self.traffic.setdefault((source, name), _MessageTraffic(msg.get_msgId(), first_us=now_us))
        traffic.count += 1
        traffic.last_us = now_us
        self.mavlink_versions.add(2 if msg.get_msgbuf()[0] == mavlink2.PROTOCOL_MARKER_V2 else 1)
        if name == "HEARTBEAT":
            self.heartbeats[source] = msg
            if msg.autopilot != mavlink2.MAV_AUTOPILOT_INVALID and self.autopilot is None:
                self.autopilot = source
        elif name == "AUTOPILOT_VERSION" and source == self.autopilot:
            self.version = msg
        elif name == "COMMAND_ACK" and msg.command == mavlink2.MAV_CMD_REQUEST_MESSAGE:
            self.version_unsupported = msg.result == mavlink2.MAV_RESULT_UNSUPPORTED

    def summary(self, endpoint: str, window_us: int, counters: LinkCounters, unknown_ids: dict[int, int]) -> dict:
        if self.autopilot is None:
            raise NoHeartbeat(f"no autopilot heartbeat on {endpoint}")
        heartbeat = self.heartbeats[self.autopilot]
        return {
            "endpoint": endpoint,
            "mavlink": sorted(self.mavlink_versions),
            "system_id": self.autopilot[0],
            "component_id": self.autopilot[1],
            "component": _enum_name("MAV_COMPONENT", self.autopilot[1], "MAV_COMP_ID_"),
            "autopilot": _enum_name("MAV_AUTOPILOT", heartbeat.autopilot, "MAV_AUTOPILOT_"),
            "vehicle_type": _enum_name("MAV_TYPE", heartbeat.type, "MAV_TYPE_"),
            "system_status": _enum_name("MAV_STATE", heartbeat.system_status, "MAV_STATE_"),
            "armed": bool(heartbeat.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED),
            "mode": mode_name(heartbeat),
            "firmware": firmware(self.version) if self.version is not None else None,
            "other_components": [
                {"system_id": s, "component_id": c, "type": _enum_name("MAV_TYPE", hb.type, "MAV_TYPE_")}
                for (s, c), hb in sorted(self.heartbeats.items())
                if (s, c) != self.autopilot
            ],
            "window_s": window_us / 1e6,
            "messages": [
                {
                    "system_id": system,
                    "component_id": component,
                    "name": name,
                    "id": t.msg_id,
                    "count": t.count,
                    "rate_hz": round(t.rate_hz(window_us), 2),
                }
                for ((system, component), name), t in sorted(self.traffic.items())
            ],
            "unknown_message_ids": {str(k): v for k, v in sorted(unknown_ids.items())},
            "link": msgspec.structs.asdict(counters),
        }


def mode_name(heartbeat: mavlink2.MAVLink_heartbeat_message) -> str:
    if not heartbeat.base_mode & mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return f"base mode 0x{heartbeat.base_mode:02x}"
    if heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_PX4:
        return px4_modes.describe(heartbeat.custom_mode)
    if heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA:
        from pymavlink import mavutil  # loads every dialect (~0.6 s), so only when an ArduPilot answers

        names = mavutil.mode_mapping_bynumber(heartbeat.type) or {}
        if heartbeat.custom_mode in names:
            return names[heartbeat.custom_mode]
    return f"custom mode {heartbeat.custom_mode}"


def firmware(version: mavlink2.MAVLink_autopilot_version_message) -> dict:
    """AUTOPILOT_VERSION decoded: flight_sw_version is major<<24 | minor<<16 | patch<<8 | FIRMWARE_VERSION_TYPE."""
    v = version.flight_sw_version
    kind = _enum_name("FIRMWARE_VERSION_TYPE", v & 0xFF, "FIRMWARE_VERSION_TYPE_").lower()
    custom = bytes(version.flight_custom_version)
    return {
        "version": f"{v >> 24 & 0xFF}.{v >> 16 & 0xFF}.{v >> 8 & 0xFF}-{kind}",
        "flight_sw_version": v,
        # PX4 copies the first 8 bytes of its git hash here as a little-endian integer
        "git_hash": custom[::-1].hex() if any(custom) else "",
        "os_sw_version": version.os_sw_version,
        "board_version": version.board_version,
        "vendor_id": version.vendor_id,
        "product_id": version.product_id,
        "uid": version.uid,
        "capabilities": [
            _enum_name("MAV_PROTOCOL_CAPABILITY", bit, "MAV_PROTOCOL_CAPABILITY_")
            for bit in (1 << i for i in range(64))
            if version.capabilities & bit
        ],
    }


def _enum_name(enum: str, value: int, prefix: str) -> str:
    entry = mavlink2.enums[enum].get(value)
    return entry.name.removeprefix(prefix) if entry is not None else str(value)


def inspect_endpoint(endpoint: str, seconds: float) -> dict:
    """Listen for ``seconds``, asking the autopilot for its version; raises NoHeartbeat if no autopilot spoke."""
    link = MavlinkLink(
        endpoint,
        system_id=INSPECTOR_SYSTEM_ID,
        component_id=INSPECTOR_COMPONENT_ID,
        heartbeat=_ground_station_heartbeat,
    )
    inspection = Inspection()
    start = monotonic_us()
    end = start + int(seconds * 1e6)
    next_request = 0
    try:
        while (now := monotonic_us()) < end:
            for msg in link.poll(min(0.05, (end - now) / 1e6)):
                inspection.observe(msg, monotonic_us())
            now = monotonic_us()
            if inspection.autopilot is not None and inspection.version is None and now >= next_request:
                next_request = now + VERSION_REQUEST_PERIOD_US
                _request_version(link, inspection)
        try:
            return inspection.summary(str(link.endpoint), end - start, link.counters, link.parser.unknown_ids)
        except NoHeartbeat as e:
            raise NoHeartbeat(_why_silent(str(e), seconds, link)) from None
    finally:
        link.close()


def _request_version(link: MavlinkLink, inspection: Inspection) -> None:
    assert inspection.autopilot is not None
    system, component = inspection.autopilot
    if inspection.version_unsupported:
        command, param1 = mavlink2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1.0
    else:
        command, param1 = mavlink2.MAV_CMD_REQUEST_MESSAGE, float(mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    link.mav.command_long_send(system, component, command, 0, param1, 0, 0, 0, 0, 0, 0)


def _ground_station_heartbeat() -> dict:
    return {
        "type": mavlink2.MAV_TYPE_GCS,
        "autopilot": mavlink2.MAV_AUTOPILOT_INVALID,
        "base_mode": 0,
        "custom_mode": 0,
        "system_status": mavlink2.MAV_STATE_ACTIVE,
    }


def _why_silent(message: str, seconds: float, link: MavlinkLink) -> str:
    c = link.counters
    if link.error is not None:
        return f"{message} in {seconds:g} s: {link.error}"
    if c.bytes_in == 0:
        return f"{message} in {seconds:g} s: nothing received"
    if c.packets_in == 0:
        return f"{message} in {seconds:g} s: {c.bytes_in} bytes received but no MAVLink frame (wrong baud rate?)"
    return f"{message} in {seconds:g} s: {c.packets_in} MAVLink packets, none a heartbeat from an autopilot"


def format_summary(summary: dict) -> str:
    """The summary as the terminal shows it."""
    lines = [
        f"endpoint   {summary['endpoint']} (MAVLink {', '.join(str(v) for v in summary['mavlink'])})",
        f"autopilot  {summary['autopilot']}, system {summary['system_id']} component {summary['component_id']}"
        f" ({summary['component']})",
        f"vehicle    {summary['vehicle_type']}, status {summary['system_status']}",
        f"state      {'ARMED' if summary['armed'] else 'disarmed'}, mode {summary['mode']}",
        f"firmware   {_format_firmware(summary['firmware'])}",
    ]
    for other in summary["other_components"]:
        lines.append(f"also       system {other['system_id']} component {other['component_id']}: {other['type']}")
    lines.append(f"messages over {summary['window_s']:g} s:")
    width = max((len(m["name"]) for m in summary["messages"]), default=4)
    lines.append(f"  {'FROM':<7}  {'NAME':<{width}}  {'ID':>5}  {'COUNT':>6}  {'RATE Hz':>8}")
    for m in summary["messages"]:
        source = f"{m['system_id']}/{m['component_id']}"
        lines.append(f"  {source:<7}  {m['name']:<{width}}  {m['id']:>5}  {m['count']:>6}  {m['rate_hz']:>8.2f}")
    if summary["unknown_message_ids"]:
        ids = ", ".join(f"{k} ({v})" for k, v in summary["unknown_message_ids"].items())
        lines.append(f"unknown    message ids (count): {ids}")
    c = summary["link"]
    lines += [
        f"link       in {c['bytes_in']} B / {c['packets_in']} packets, out {c['bytes_out']} B / {c['packets_out']}"
        f" packets, quality {c['quality']:.0%}",
        f"errors     crc {c['crc_errors']}, parse {c['parse_errors']}, unknown {c['unknown_messages']},"
        f" lost (by sequence) {c['seq_gaps']}, link losses {c['link_losses']}, send drops {c['send_drops']}",
    ]
    return "\n".join(lines)


def _format_firmware(fw: dict | None) -> str:
    if fw is None:
        return "unknown (no AUTOPILOT_VERSION received)"
    text = fw["version"]
    if fw["git_hash"]:
        text += f" (git {fw['git_hash']})"
    return text + f", vendor 0x{fw['vendor_id']:04x} product 0x{fw['product_id']:04x}"
