"""The vehicle's summary in `stack status`, as PX4's `commander status` gives it: mode by name, armed,
failsafe and its cause, position (local NED and altitude) and battery, from the vehicle's latest messages
and the commander's heartbeat figures."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

from stack.bus.node import Node
from stack.cli.common import wait_until_sent
from stack.commander.modes import mode_name
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.system import BatteryStatus, HomePosition, VehicleStatus

TOPICS = ("vehicle_status", "vehicle_local_position", "home_position", "battery_status")
SUMMARY_WAIT_S = 2.0
"""Wall-clock seconds a summary waits for the vehicle's messages (vehicle_status comes at 2 Hz at least)."""
BATTERY_WARNINGS = {
    v: k.removeprefix("WARNING_").lower() for k, v in vars(BatteryStatus).items() if k.startswith("WARNING_")
}


def latest(nodes: Sequence[Node]) -> dict[str, dict[str, Any]]:
    """Vehicle → the next message of each of :data:`TOPICS` of it (those that came), each node a vehicle's, waiting at
    most SUMMARY_WAIT_S for them all."""
    subs = {node.vehicle: {topic: node.subscriber(topic, keep_last=True) for topic in TOPICS} for node in nodes}
    for node in nodes:
        wait_until_sent(node, [(topic, 0) for topic in TOPICS])
    out: dict[str, dict[str, Any]] = {vehicle: {} for vehicle in subs}
    deadline = time.monotonic() + SUMMARY_WAIT_S
    while any(len(out[v]) < len(TOPICS) for v in subs) and time.monotonic() < deadline:
        for vehicle, topics in subs.items():
            for name, sub in topics.items():
                while (item := sub.poll()) is not None:
                    out[vehicle][name] = item.msg
        time.sleep(0.01)
    return out


def commander_figures(report: dict[str, Any]) -> dict[str, Any] | None:
    """The commander's heartbeat figures in a vehicle's status report (None without a commander)."""
    return next((m["extra"] for m in report.get("modules", []) if "failsafe_action" in m.get("extra", {})), None)


def add_summaries(reports: dict[str, dict[str, Any]], nodes: Sequence[Node]) -> None:
    """Each vehicle's status report (by vehicle) with a commander gains its ``vehicle_summary``, from the messages
    its node (one per vehicle) takes in, all waited for at once."""
    with_commander = {v: c for v, r in reports.items() if (c := commander_figures(r)) is not None}
    for vehicle, messages in latest([n for n in nodes if n.vehicle in with_commander]).items():
        reports[vehicle]["vehicle_summary"] = summary(messages, with_commander[vehicle])


def summary(latest: dict[str, Any], commander: dict[str, Any] | None) -> dict[str, Any]:
    """The summary as JSON-able values from the latest message of each of :data:`TOPICS` (those seen) and
    the commander's heartbeat figures (None without a commander)."""
    out: dict[str, Any] = {}
    status: VehicleStatus | None = latest.get("vehicle_status")
    if status is not None:
        out["mode"] = mode_name(status.nav_state)
        out["nav_state"] = status.nav_state
        out["armed"] = status.arming_state == VehicleStatus.ARMING_STATE_ARMED
        out["failsafe"] = status.failsafe
        out["control_lost_modules"] = list(status.control_lost_modules)
    if commander:
        out["failsafe_action"] = commander.get("failsafe_action", "none")
        out["failsafe_cause"] = commander.get("failsafe_cause", "")
    lpos: VehicleLocalPosition | None = latest.get("vehicle_local_position")
    if lpos is not None:
        home: HomePosition | None = latest.get("home_position")
        home_z = home.z if home is not None and home.valid_lpos else math.nan
        out["position"] = {
            "north": lpos.x,
            "east": lpos.y,
            "down": lpos.z,
            "xy_valid": lpos.xy_valid,
            "z_valid": lpos.z_valid,
            "altitude_above_home": home_z - lpos.z,
            "altitude_amsl": lpos.ref_alt - lpos.z,
        }
    battery: BatteryStatus | None = latest.get("battery_status")
    if battery is not None:
        out["battery"] = {
            "voltage_v": battery.voltage_v,
            "current_a": battery.current_a,
            "remaining": battery.remaining,
            "warning": BATTERY_WARNINGS.get(battery.warning, str(battery.warning)),
        }
    return out


def lines(s: dict[str, Any]) -> list[str]:
    """The summary in words."""
    if "mode" not in s:
        return ["vehicle: no vehicle_status (is a commander running?)"]
    failsafe = "no"
    if s["failsafe"] or s.get("failsafe_action", "none") != "none":
        cause = f" ({s['failsafe_cause']})" if s.get("failsafe_cause") else ""
        failsafe = f"{s.get('failsafe_action', 'yes')}{cause}"
    out = [f"vehicle: {s['mode']}, {'armed' if s['armed'] else 'disarmed'}, failsafe: {failsafe}"]
    if s.get("control_lost_modules"):
        out.append(f"control chain: {', '.join(s['control_lost_modules'])} dead or silent")
    if (p := s.get("position")) is not None:
        valid = "valid" if p["xy_valid"] and p["z_valid"] else "NOT valid"
        out.append(
            f"position: N {p['north']:.2f} E {p['east']:.2f} D {p['down']:.2f} m (local NED, {valid}), "
            f"altitude {p['altitude_above_home']:.2f} m above home, {p['altitude_amsl']:.1f} m AMSL"
        )
    if (b := s.get("battery")) is not None:
        remaining = f"{b['remaining'] * 100:.0f} %" if b["remaining"] >= 0 else "unknown"
        current = f"{b['current_a']:.1f} A" if b["current_a"] >= 0 else "current unknown"
        out.append(f"battery: {b['voltage_v']:.2f} V, {current}, {remaining} remaining, warning {b['warning']}")
    return out
