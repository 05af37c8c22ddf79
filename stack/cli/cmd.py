"""``stack cmd``: command the vehicle as a ground station does, and print the commander's acknowledgement.

Each command is one ``vehicle_command`` from system 255 (a ground station) and component 190
(MAV_COMP_ID_MISSIONPLANNER); the acknowledgement addressed back to that pair is the answer, so several
tools can command one vehicle at once. A refused command prints ``<RESULT>: <reason>`` and exits with
1; input that cannot be sent (a non-finite number, an unknown mode, a broken mission file) exits with 2
and sends nothing. ``--wait`` then follows the action on the vehicle's topics until it completes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgspec
import typer

from stack.bus.node import Node
from stack.bus.topics import TopicPublisher
from stack.cli.common import EndpointOption, VehicleOption, connect, fail, wait_until_sent
from stack.commander import commands
from stack.commander.modes import MODES, mode_name, nav_state_from_name
from stack.mathlib.geo import MapProjection
from stack.mission.items import (
    GLOBAL_AMSL_FRAMES,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    GeoPoint,
    Mission,
    MissionError,
)
from stack.mission.loader import load_mission
from stack.mission.transfer import mission_id_for, mission_message
from stack.msg.base import Message
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.system import RESULT_NAMES, VehicleCommand, VehicleCommandAck, VehicleStatus

app = typer.Typer(
    help="Command the vehicle (arm, takeoff, goto, modes, missions...) and print the acknowledgement.",
    no_args_is_help=True,
)

ACK = VehicleCommandAck
NS = VehicleStatus
CLI_SYSTEM = 255
"""MAVLink system id of a ground station."""
CLI_COMPONENT = 190
"""MAV_COMP_ID_MISSIONPLANNER: the acknowledgements addressed to this pair are ours."""
HOME_WAIT_S = 1.5
REACHED_M = 1.0
POLL_S = 0.01
NO_COMMANDER = "no commander is running (nothing subscribes to vehicle_command)"
NO_NAVIGATOR = "no answer from the navigator (is flight_mode_manager running?)"
WATCHED = ("vehicle_status", "vehicle_local_position")

TimeoutOption = typer.Option(
    5.0, "--timeout", "-t", help="Seconds to wait for the answer (and, with --wait, for the action)"
)
WaitOption = typer.Option(False, "--wait", "-w", help="Wait until the action completes, printing progress")
YawOption = typer.Option(None, "--yaw", help="Heading in degrees (default: keep the current one)")

New = list[tuple[str, Message]]
"""Messages received by one poll: (topic, message)."""


class _Link:
    """One session with the vehicle. The acknowledgement and watched topics are subscribed to before
    anything is sent, so no answer is missed; into ring buffers, so a slow reader never holds up the bus."""

    def __init__(self, node: Node, timeout: float, watch: tuple[str, ...] = ()) -> None:
        self.node = node
        self.timeout = timeout
        self._acks = node.subscriber("vehicle_command_ack", keep_last=True)
        self._watched = {topic: node.subscriber(topic, keep_last=True) for topic in watch}
        wait_until_sent(node, [("vehicle_command_ack", 0), *((topic, 0) for topic in watch)])
        self._after: tuple[int, int] | None = None
        self.latest: dict[str, Any] = {}

    def poll(self) -> New:
        """Drain the watched topics; ``vehicle_status`` counts only once published after the last ack."""
        new: New = []
        for topic, sub in self._watched.items():
            while (item := sub.poll()) is not None:
                _, publisher, seq, msg, _ = item
                if topic == "vehicle_status" and self._after is not None:
                    ack_publisher, ack_seq = self._after
                    if publisher == ack_publisher and seq <= ack_seq:
                        continue
                self.latest[topic] = msg
                new.append((topic, msg))
        return new

    def publisher(self, topic: str, nobody: str) -> TopicPublisher:
        """A publisher once a subscriber matches (so the first message is not lost); ``nobody`` if none does."""
        publisher = self.node.publisher(topic)
        deadline = time.monotonic() + self.timeout
        while not publisher.matching():
            if time.monotonic() >= deadline:
                fail(nobody)
            time.sleep(POLL_S)
        return publisher

    def command(self, cmd: VehicleCommand, label: str) -> VehicleCommandAck:
        """Send ``cmd``, print its acknowledgement; exit non-zero unless it was accepted."""
        cmd = msgspec.structs.replace(cmd, source_system=CLI_SYSTEM, source_component=CLI_COMPONENT)
        self.publisher("vehicle_command", NO_COMMANDER).publish(cmd)
        deadline = time.monotonic() + self.timeout
        while True:
            item = self._acks.poll()
            if item is None:
                if time.monotonic() >= deadline:
                    fail(f"{label}: no acknowledgement within {self.timeout:g} s (is the commander running?)")
                time.sleep(POLL_S)
                continue
            _, publisher, seq, ack, _ = item
            if (ack.command, ack.target_system, ack.target_component) == (cmd.command, CLI_SYSTEM, CLI_COMPONENT):
                break
        self._after = (publisher, seq)
        self.latest.pop("vehicle_status", None)
        if ack.result != ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            result = RESULT_NAMES.get(ack.result, f"result {ack.result}")
            typer.echo(f"{label}: {result}" + (f": {ack.reason}" if ack.reason else ""), err=True)
            raise typer.Exit(1)
        typer.echo(f"{label}: accepted")
        return ack

    def wait_for(self, what: str, check: Callable[[New], str | None], progress: Callable[[], str]) -> None:
        """Poll until ``check`` returns the completion message (it fails itself when the action cannot
        complete), printing ``progress`` every second; fail after the timeout."""
        deadline = time.monotonic() + self.timeout
        report = time.monotonic() + 1.0
        while (done := check(self.poll())) is None:
            now = time.monotonic()
            if now >= deadline:
                fail(f"{what}: not done within {self.timeout:g} s ({progress()})")
            if now >= report:
                report += 1.0
                typer.echo(progress())
            time.sleep(POLL_S)
        typer.echo(done)

    def status(self) -> VehicleStatus | None:
        return self.latest.get("vehicle_status")

    def position(self) -> VehicleLocalPosition | None:
        return self.latest.get("vehicle_local_position")

    def state(self) -> str:
        """The vehicle's height and mode in words, for progress lines."""
        parts = []
        lpos, status = self.position(), self.status()
        if lpos is not None:
            parts.append(f"altitude {0.0 - lpos.z:.1f} m")
        if status is not None:
            armed = status.arming_state == NS.ARMING_STATE_ARMED
            parts.append(mode_name(status.nav_state) + ("" if armed else " (disarmed)"))
        return ", ".join(parts) or "no vehicle state yet"

    def disarmed(self) -> bool:
        status = self.status()
        return status is not None and status.arming_state != NS.ARMING_STATE_ARMED


def _send(
    cmd: VehicleCommand,
    label: str,
    vehicle: str | None,
    endpoint: str | None,
    timeout: float,
    wait: Callable[[_Link], None] | None = None,
) -> None:
    with connect(vehicle, endpoint) as node:
        link = _Link(node, timeout, WATCHED if wait else ())
        link.command(cmd, label)
        if wait is not None:
            wait(link)


def _finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        fail(f"{name} must be a finite number, got {value:g}; nothing sent", code=2)
    return value


def _optional(name: str, value: float | None) -> float:
    """A number the user may leave out (NaN to the commander)."""
    return math.nan if value is None else _finite(name, value)


def _wait_disarmed(label: str) -> Callable[[_Link], None]:
    def wait(link: _Link) -> None:
        link.wait_for(label, lambda _: f"{label}: landed and disarmed" if link.disarmed() else None, link.state)

    return wait


@app.command()
def arm(
    force: bool = typer.Option(False, "--force", help="Skip the pre-arm checks"),
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Arm the motors (after the pre-arm checks)."""
    _send(commands.arm_command(force), "arm", vehicle, endpoint, timeout)


@app.command()
def disarm(
    force: bool = typer.Option(False, "--force", help="Disarm even when not landed"),
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Disarm the motors (only when landed, unless --force)."""
    _send(commands.disarm_command(force), "disarm", vehicle, endpoint, timeout)


@app.command()
def takeoff(
    alt: float | None = typer.Option(None, "--alt", help="Metres above home (default: MIS_TAKEOFF_ALT)"),
    yaw: float | None = YawOption,
    wait: bool = WaitOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Take off (arming first if needed) and hold at the takeoff altitude."""
    cmd = commands.takeoff_command(_optional("--alt", alt), relative=True, yaw_deg=_optional("--yaw", yaw))

    def until_airborne(link: _Link) -> None:
        def check(_: New) -> str | None:
            status = link.status()
            if link.disarmed():
                fail("takeoff: the vehicle disarmed")
            if status is None or status.nav_state == NS.NAVIGATION_STATE_AUTO_TAKEOFF:
                return None
            if status.nav_state not in (NS.NAVIGATION_STATE_AUTO_LOITER, NS.NAVIGATION_STATE_AUTO_MISSION):
                fail(f"takeoff interrupted: now in {mode_name(status.nav_state)}")
            return f"takeoff complete: {link.state()}"

        link.wait_for("takeoff", check, link.state)

    _send(cmd, "takeoff", vehicle, endpoint, timeout, until_airborne if wait else None)


@app.command()
def land(
    wait: bool = WaitOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Land where the vehicle is."""
    _send(commands.land_command(), "land", vehicle, endpoint, timeout, _wait_disarmed("land") if wait else None)


@app.command()
def hold(
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Hold position (PX4's Hold / auto:loiter)."""
    _send(commands.hold_command(), "hold", vehicle, endpoint, timeout)


@app.command()
def rtl(
    wait: bool = WaitOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Return to home and land."""
    _send(commands.return_command(), "rtl", vehicle, endpoint, timeout, _wait_disarmed("rtl") if wait else None)


app.command("return", help="Return to home and land (same as rtl).")(rtl)


@app.command(context_settings={"ignore_unknown_options": True})
def goto(
    north: float | None = typer.Argument(None, help="North (m, local NED)", show_default=False),
    east: float | None = typer.Argument(None, help="East (m)", show_default=False),
    down: float | None = typer.Argument(None, help="Down (m; negative is up)", show_default=False),
    lat: float | None = typer.Option(None, "--lat", help="Latitude (deg), instead of N E D"),
    lon: float | None = typer.Option(None, "--lon", help="Longitude (deg), with --lat"),
    alt: float | None = typer.Option(None, "--alt", help="Altitude AMSL (m) with --lat/--lon (default: keep)"),
    yaw: float | None = YawOption,
    speed: float | None = typer.Option(None, "--speed", help="Ground speed in m/s (default: the cruise speed)"),
    wait: bool = WaitOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Fly to a local position N E D (metres) about the local origin (or --lat/--lon [--alt]) and hold there."""
    local = (north, east, down)
    yaw_deg, speed_ms = _optional("--yaw", yaw), _optional("--speed", speed)
    if lat is None and lon is None and alt is None:
        if north is None or east is None or down is None:
            fail("give the target as N E D (metres, local NED) or as --lat/--lon [--alt]; nothing sent", code=2)
        n, e, d = _finite("north", north), _finite("east", east), _finite("down", down)
        cmd = commands.goto_local_command(n, e, d, yaw_deg, speed_ms)

        def target(_: VehicleLocalPosition) -> tuple[float, float, float]:
            return (n, e, d)

    else:
        if local != (None, None, None) or lat is None or lon is None:
            fail("a global target needs both --lat and --lon (and no N E D); nothing sent", code=2)
        la, lo, al = _finite("--lat", lat), _finite("--lon", lon), _optional("--alt", alt)
        cmd = commands.goto_global_command(la, lo, al, yaw_deg, speed_ms)

        def target(lpos: VehicleLocalPosition) -> tuple[float, float, float]:
            n, e = MapProjection(lpos.ref_lat, lpos.ref_lon).project(la, lo)
            return (n, e, lpos.ref_alt - al)

    def until_there(link: _Link) -> None:
        def distance() -> float:
            lpos = link.position()
            if lpos is None:
                return math.nan
            here = (lpos.x, lpos.y, lpos.z)
            return math.sqrt(sum((t - p) ** 2 for t, p in zip(target(lpos), here, strict=True) if not math.isnan(t)))

        def check(_: New) -> str | None:
            status = link.status()
            if link.disarmed():
                fail("goto: the vehicle disarmed")
            if status is not None and status.nav_state != NS.NAVIGATION_STATE_AUTO_LOITER:
                fail(f"goto interrupted: now in {mode_name(status.nav_state)}")
            return f"goto: reached ({link.state()})" if distance() <= REACHED_M else None

        link.wait_for("goto", check, lambda: f"{distance():.1f} m to go, {link.state()}")

    _send(cmd, "goto", vehicle, endpoint, timeout, until_there if wait else None)


@app.command()
def mode(
    name: str = typer.Argument(..., help="PX4 mode name: manual, stabilized, acro, altctl, posctl, auto:loiter..."),
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Switch flight mode (DO_SET_MODE with PX4's custom mode, as QGroundControl sends it)."""
    try:
        nav_state = nav_state_from_name(name)
    except ValueError as e:
        fail(f"{e}; nothing sent", code=2)
    _send(commands.set_mode_command(name), f"mode {MODES[nav_state].name}", vehicle, endpoint, timeout)


def _vehicle_home(link: _Link) -> tuple[GeoPoint | None, str]:
    """The vehicle's home from ``home_position``; failing that, where it is (``vehicle_local_position``)."""
    deadline = time.monotonic() + HOME_WAIT_S
    while time.monotonic() < deadline:
        link.poll()
        home = link.latest.get("home_position")
        if home is not None and home.valid_hpos and math.isfinite(home.lat) and math.isfinite(home.lon):
            return GeoPoint(home.lat, home.lon, home.alt), "the vehicle's home"
        time.sleep(POLL_S)
    lpos = link.position()
    if lpos is not None and lpos.xy_valid and all(map(math.isfinite, (lpos.ref_lat, lpos.ref_lon, lpos.ref_alt))):
        lat, lon = MapProjection(lpos.ref_lat, lpos.ref_lon).reproject(lpos.x, lpos.y)
        return GeoPoint(lat, lon, lpos.ref_alt - lpos.z), "the vehicle's position (no home set yet)"
    return None, ""


def _needs_home(mission: Mission) -> bool:
    """Whether the mission has geodetic positions (which only the vehicle's home can place)."""
    return any(math.isfinite(i.lat) or (i.frame in GLOBAL_AMSL_FRAMES and math.isfinite(i.alt)) for i in mission)


def _upload(link: _Link, mission: Mission, home: GeoPoint | None) -> MissionResult:
    """Publish the mission and wait for the navigator's verdict (returned when valid)."""
    ident = mission_id_for(mission)
    publisher = link.publisher("mission", f"{NO_NAVIGATOR}: nothing subscribes to mission")
    publisher.publish(mission_message(mission, home, ident))
    deadline = time.monotonic() + link.timeout
    while True:
        for topic, msg in link.poll():
            if topic == "mission_result" and msg.mission_id == ident:
                if not msg.valid:
                    fail(f"mission rejected: {msg.reason or 'invalid'}")
                count = f"{len(mission)} item{'s' if len(mission) != 1 else ''}"
                typer.echo(f"mission accepted: {count}" + (f" (warning: {msg.reason})" if msg.warning else ""))
                return msg
        if time.monotonic() >= deadline:
            fail(NO_NAVIGATOR)
        time.sleep(POLL_S)


def _until_commander_knows(link: _Link, result: MissionResult) -> None:
    """Wait (at most the timeout) for a ``vehicle_status`` published after the navigator's verdict: the
    commander counts the mission from its next cycle on (in lockstep, a module never sees what another
    published at the same simulated time), and a start handled before would find no mission."""
    deadline = time.monotonic() + link.timeout
    while time.monotonic() < deadline:
        if any(topic == "vehicle_status" and msg.timestamp > result.timestamp for topic, msg in link.poll()):
            return
        time.sleep(POLL_S)


def _until_finished(link: _Link, mission: Mission, ident: int, start: VehicleCommandAck) -> None:
    """Wait for the end of the mission (and the landing, if it ends with one); only results published
    after the start count."""
    lands = len(mission) > 0 and mission[-1].command in (MAV_CMD_NAV_LAND, MAV_CMD_NAV_RETURN_TO_LAUNCH)
    progress: list[MissionResult] = []

    def check(new: New) -> str | None:
        for topic, msg in new:
            if topic == "mission_result" and msg.mission_id == ident and msg.timestamp > start.timestamp:
                if msg.failure:
                    fail(f"mission failed: {msg.reason or f'at item {msg.seq_current}'}")
                progress.append(msg)
        finished = bool(progress) and progress[-1].finished
        if link.disarmed() and not finished:
            fail("mission: the vehicle disarmed before the end of the mission")
        if finished and (link.disarmed() or not lands):
            return "mission finished" + (", landed and disarmed" if lands else "")
        return None

    def describe() -> str:
        item = f"item {progress[-1].seq_current + 1}/{progress[-1].seq_total}, " if progress else ""
        return item + link.state()

    link.wait_for("mission", check, describe)


@app.command("mission")
def mission_(
    file: Path = typer.Argument(..., help="QGroundControl .plan, QGC WPL 110 or a simple waypoint list"),
    no_start: bool = typer.Option(False, "--no-start", help="Upload only; do not start the mission"),
    first: int = typer.Option(0, "--first", help="Item to start at (−1: the current one)"),
    wait: bool = WaitOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Upload a mission (global positions placed about the vehicle's home) and start it."""
    with connect(vehicle, endpoint) as node:
        link = _Link(node, timeout, ("home_position", "mission_result", *WATCHED))
        home, origin = _vehicle_home(link)
        try:
            mission = load_mission(file, home)
        except MissionError as e:
            fail(str(e), code=2)
        if home is None and _needs_home(mission):
            fail(
                f"{file}: the vehicle has no home position yet (no home_position or vehicle_local_position), "
                "so the mission's geodetic positions cannot be placed; nothing sent",
                code=2,
            )
        if home is not None:
            typer.echo(f"home: {home.lat:.7f}, {home.lon:.7f}, {home.alt:.1f} m AMSL ({origin})")
        result = _upload(link, mission, home)
        if no_start:
            return
        _until_commander_knows(link, result)
        start = link.command(commands.mission_start_command(first), "mission start")
        if wait:
            _until_finished(link, mission, result.mission_id, start)
