"""``stack cmd``: command the vehicle as a ground station does, and print the commander's acknowledgement.

Each command is one ``vehicle_command`` from system 255 (a ground station) and component 190
(MAV_COMP_ID_MISSIONPLANNER); the acknowledgement addressed back to that pair is the answer, so several
tools can command one vehicle at once. A refused command prints ``<RESULT>: <reason>`` and exits with
1; input that cannot be sent (a non-finite number, an unknown mode, a broken mission file) exits with 2
and sends nothing. ``--wait`` then follows the action on the vehicle's topics until it completes
(:mod:`stack.cli.follow`), and exits with 1 when it did not.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any, NoReturn

import msgspec
import typer

from stack.bus.node import Node
from stack.bus.supervisors import vehicle_status
from stack.bus.topics import MessageTooLarge, TopicPublisher
from stack.cli.common import (
    EndpointOption,
    VehicleOption,
    check_may_command,
    command_group,
    connect,
    connect_all,
    fail,
    number,
    wait_until_sent,
)
from stack.cli.follow import (
    GOTO_MODES,
    LAND_MODES,
    MISSION_MODES,
    RETURN_MODES,
    TAKEOFF_MODES,
    Action,
    Goto,
    Land,
    MissionRun,
    Progress,
    Return,
    Takeoff,
    Vehicle,
    budget_s,
)
from stack.cli.follow import PARAMS as FOLLOW_PARAMS
from stack.commander import commands
from stack.commander.command_checks import BROADCAST
from stack.commander.modes import MODES, nav_state_from_name
from stack.launch_files import find_mission
from stack.mathlib.geo import MapProjection
from stack.mission.items import GLOBAL_AMSL_FRAMES, GeoPoint, Mission, MissionError
from stack.mission.loader import load_mission
from stack.mission.transfer import mission_id_for, mission_message, too_many_items
from stack.msg.base import Message
from stack.msg.estimation import VehicleLocalPosition
from stack.msg.navigation import MissionResult
from stack.msg.system import RESULT_NAMES, VehicleCommand, VehicleCommandAck, VehicleStatus
from stack.params import catalogue, client
from stack.runtime.pacing import MAX_SPEED, describe_speed

app = command_group(
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
POLL_S = 0.01
PROGRESS_S = 1.0
"""Wall-clock seconds between looks at the progress: a line is printed when it changed."""
SILENT_S = 15.0
"""Wall-clock seconds without a message from the vehicle after which --wait gives up (the stack stopped)."""
CAUSE_WAIT_S = 2.0
"""How long a failure waits for the commander's word on why a failsafe took over: ``mavlink_log`` and
``vehicle_status`` are separate topics, so the cause may arrive just after the state."""
NO_COMMANDER = "no commander is running (nothing subscribes to vehicle_command)"
NO_NAVIGATOR = "no answer from the navigator (is flight_mode_manager running?)"
WATCHED = ("vehicle_status", "vehicle_local_position", "home_position", "mavlink_log")

TimeoutOption = typer.Option(
    5.0, "--timeout", "-t", callback=number(above=0), help="Seconds to wait for the acknowledgement"
)
WaitOption = typer.Option(
    False, "--wait", "-w", help="Follow the action until it completes, printing progress; exit 1 if it fails"
)
WaitTimeoutOption = typer.Option(
    None,
    "--wait-timeout",
    callback=number(above=0),
    help="With --wait: seconds the action may take, simulated in lockstep (default: sized to the action "
    "from its distances and the vehicle's speed parameters)",
    show_default=False,
)
AllOption = typer.Option(
    False, "--all", help="Every vehicle on the bus at once (each answers for itself; the exit code is the worst)"
)
YawOption = typer.Option(None, "--yaw", help="Heading in degrees (default: keep the current one)")

New = list[tuple[str, Message]]
"""Messages received by one poll: (topic, message)."""


def from_ground_station(cmd: VehicleCommand) -> VehicleCommand:
    """``cmd`` as the CLI sends it: from a ground station's system and component, to whatever system and component
    the vehicle is (its topic key already names it; a swarm's vehicle i is MAVLink system i)."""
    return msgspec.structs.replace(
        cmd,
        source_system=CLI_SYSTEM,
        source_component=CLI_COMPONENT,
        target_system=BROADCAST,
        target_component=BROADCAST,
    )


def answers(ack: VehicleCommandAck, cmd: VehicleCommand) -> bool:
    """Whether ``ack`` is the commander's answer to ``cmd`` as :func:`from_ground_station` sent it."""
    return (ack.command, ack.target_system, ack.target_component) == (cmd.command, CLI_SYSTEM, CLI_COMPONENT)


def outcome(label: str, ack: VehicleCommandAck) -> str:
    """``<label>: accepted``, or ``<label>: <RESULT>: <reason>``."""
    if ack.result == ACK.VEHICLE_CMD_RESULT_ACCEPTED:
        return f"{label}: accepted"
    result = RESULT_NAMES.get(ack.result, f"result {ack.result}")
    return f"{label}: {result}" + (f": {ack.reason}" if ack.reason else "")


class _Link:
    """One session with the vehicle. The acknowledgement and watched topics are subscribed to before
    anything is sent, so no answer is missed; into ring buffers, so a slow reader never holds up the bus."""

    def __init__(self, node: Node, timeout: float, watch: tuple[str, ...] = (), prefix: str = "") -> None:
        """``prefix`` starts every line it prints (the vehicle's name, when several are commanded at once)."""
        self.node = node
        self.timeout = timeout
        self.prefix = prefix
        self._acks = node.subscriber("vehicle_command_ack", keep_last=True)
        self._watched = {topic: node.subscriber(topic, keep_last=True) for topic in watch}
        wait_until_sent(node, [("vehicle_command_ack", 0), *((topic, 0) for topic in watch)])
        self._after: tuple[int, int] | None = None
        self.latest: dict[str, Any] = {}
        self.vehicle = Vehicle()
        self.heard = time.monotonic()
        """When the last watched message arrived (wall clock)."""

    def say(self, line: str) -> None:
        typer.echo(self.prefix + line)

    def fail(self, message: str, error: bool = True) -> NoReturn:
        """Print ``message`` on stderr (as an ``error:`` unless ``error`` is False: a refusal is the vehicle's
        answer) and exit 1."""
        typer.echo(f"{'error: ' if error else ''}{self.prefix}{message}", err=True)
        raise typer.Exit(1)

    def poll(self) -> New:
        """Drain the watched topics; ``vehicle_status`` counts only once published after the last ack."""
        new: New = []
        for topic, sub in self._watched.items():
            while (item := sub.poll()) is not None:
                publisher, seq, msg = item.publisher, item.seq, item.msg
                if topic == "vehicle_status" and self._after is not None:
                    ack_publisher, ack_seq = self._after
                    if publisher == ack_publisher and seq <= ack_seq:
                        continue
                self.latest[topic] = msg
                self.vehicle.update(topic, msg)
                self.heard = time.monotonic()
                new.append((topic, msg))
        return new

    def publisher(self, topic: str, nobody: str) -> TopicPublisher:
        """A publisher once a subscriber matches (so the first message is not lost); ``nobody`` if none does."""
        publisher = self.node.publisher(topic)
        deadline = time.monotonic() + self.timeout
        while not publisher.matching():
            if time.monotonic() >= deadline:
                self.fail(nobody)
            time.sleep(POLL_S)
        return publisher

    def command(self, cmd: VehicleCommand, label: str) -> VehicleCommandAck:
        """Send ``cmd``, print its acknowledgement; exit non-zero unless it was accepted."""
        cmd = from_ground_station(cmd)
        self.publisher("vehicle_command", NO_COMMANDER).publish(cmd)
        deadline = time.monotonic() + self.timeout
        while True:
            item = self._acks.poll()
            if item is None:
                if time.monotonic() >= deadline:
                    self.fail(f"{label}: no acknowledgement within {self.timeout:g} s (is the commander running?)")
                time.sleep(POLL_S)
                continue
            publisher, seq, ack = item.publisher, item.seq, item.msg
            if answers(ack, cmd):
                break
        self._after = (publisher, seq)
        self.latest.pop("vehicle_status", None)
        self.vehicle.status = None
        if ack.result != ACK.VEHICLE_CMD_RESULT_ACCEPTED:
            self.fail(outcome(label, ack), error=False)
        self.say(outcome(label, ack))
        return ack

    def follow(self, action: Action, start: VehicleCommandAck, limit_s: float | None) -> None:
        """Follow ``action`` from its acknowledgement ``start`` until it is done (exit 0) or failed (exit 1),
        printing progress and the commander's messages; the time it may take is counted on the vehicle's
        clock in lockstep (simulated seconds), on the wall clock otherwise."""
        action.p = vehicle_params(self.node)
        lockstep = is_lockstep(self.node)
        clock = "simulated " if lockstep else ""
        began = time.monotonic()
        budget: float | None = limit_s
        report = began + PROGRESS_S
        progress = Progress()
        explain_by = 0.0
        while True:
            for topic, msg in self.poll():
                if topic == "mavlink_log" and msg.timestamp >= start.timestamp:
                    self.say(f"vehicle: {msg.text}")
            v = self.vehicle
            if (failure := action.failed(v)) is not None:
                unexplained = v.status is not None and v.status.failsafe and not v.failsafe_explained()
                explain_by = explain_by or time.monotonic() + CAUSE_WAIT_S
                if not unexplained or time.monotonic() >= explain_by:
                    self.fail(failure)
            if (done := action.done(v)) is not None:
                self.say(done)
                return
            now = time.monotonic()
            if budget is None and v.status is not None and v.position is not None:
                budget = budget_s(action.nominal_s(v))
                self.say(f"{action.name}: following, for at most {budget:.0f} s ({clock}time)")
            elapsed = (v.now_us - start.timestamp) / 1e6 if lockstep else now - began
            if budget is not None and elapsed > budget:
                self.fail(f"{action.name}: not done within {budget:.0f} s of {clock}time ({action.progress(v)})")
            if now - self.heard > SILENT_S:
                self.fail(f"{action.name}: nothing heard from the vehicle for {SILENT_S:g} s (did the stack stop?)")
            if now >= report:
                report += PROGRESS_S
                if progress.due(action.progress(v), now):
                    self.say(progress.line)
            time.sleep(POLL_S)


def is_lockstep(node: Node) -> bool:
    """Whether the stack runs in lockstep (its supervisor says; a stack reached by endpoint alone may not)."""
    status = vehicle_status(node.session, node.vehicle)
    return bool(status and status.get("lockstep"))


def clock_of(node: Node) -> str:
    """How the stack's clock runs, for a person flying it: real time, or lockstep and its pace."""
    status = vehicle_status(node.session, node.vehicle)
    if not (status and status.get("lockstep")):
        return "real time"
    speed = float(status.get("speed", MAX_SPEED))
    if speed == 1.0:
        return "lockstep at real speed"
    return f"lockstep {describe_speed(speed)}: simulated time does not run at the wall clock's pace"


def vehicle_params(node: Node, names: tuple[str, ...] = FOLLOW_PARAMS) -> dict[str, float]:
    """Parameters as the running stack holds them (else their defaults); by default those actions are sized with."""
    values = {name: float(catalogue.get(name).default) for name in names}
    for sp in client.list_params(node.session, node.vehicle):
        if sp.name in values:
            values[sp.name] = float(sp.value)
    return values


def _send(
    cmd: VehicleCommand,
    label: str,
    vehicle: str | None,
    endpoint: str | None,
    timeout: float,
    action: Action | None = None,
    limit_s: float | None = None,
    every: bool = False,
) -> None:
    """Send ``cmd``; with an ``action``, follow it (``limit_s``: the time it may take, else sized to it). With
    ``every``, to every vehicle on the bus at once, each line its vehicle's; the exit code is the worst."""
    check_may_command(endpoint)
    if every:
        if vehicle is not None:
            fail("--all addresses every vehicle: give it or --vehicle, not both; nothing sent", code=2)
        with connect_all(endpoint) as nodes:
            links = [_Link(node, timeout, WATCHED if action else (), prefix=f"{node.vehicle}: ") for node in nodes]
            raise typer.Exit(max(together([partial(_command, link, cmd, label, action, limit_s) for link in links])))
    with connect(vehicle, endpoint) as node:
        _command(_Link(node, timeout, WATCHED if action else ()), cmd, label, action, limit_s)


def _command(link: _Link, cmd: VehicleCommand, label: str, action: Action | None, limit_s: float | None) -> None:
    ack = link.command(cmd, label)
    if action is not None:
        link.follow(action, ack, limit_s)


def together(calls: list[Callable[[], None]]) -> list[int]:
    """Run ``calls`` in threads at once: the exit code of each (0 unless it raised typer.Exit)."""
    codes = [0] * len(calls)

    def run(i: int) -> None:
        try:
            calls[i]()
        except typer.Exit as e:
            codes[i] = e.exit_code

    threads = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(len(calls))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return codes


def _finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        fail(f"{name} must be a finite number, got {value:g}; nothing sent", code=2)
    return value


def _optional(name: str, value: float | None) -> float:
    """A number the user may leave out (NaN to the commander)."""
    return math.nan if value is None else _finite(name, value)


@app.command()
def arm(
    force: bool = typer.Option(False, "--force", help="Skip the pre-arm checks"),
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Arm the motors (after the pre-arm checks)."""
    _send(commands.arm_command(force), "arm", vehicle, endpoint, timeout, every=every)


@app.command()
def disarm(
    force: bool = typer.Option(False, "--force", help="Disarm even when not landed"),
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Disarm the motors (only when landed, unless --force)."""
    _send(commands.disarm_command(force), "disarm", vehicle, endpoint, timeout, every=every)


@app.command()
def takeoff(
    alt: float | None = typer.Option(None, "--alt", help="Metres above home (default: MIS_TAKEOFF_ALT)"),
    yaw: float | None = YawOption,
    wait: bool = WaitOption,
    wait_timeout: float | None = WaitTimeoutOption,
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Take off (arming first if needed) and hold at the takeoff altitude; --wait until it is reached."""
    height = _optional("--alt", alt)
    cmd = commands.takeoff_command(height, relative=True, yaw_deg=_optional("--yaw", yaw))
    action = Takeoff("takeoff", TAKEOFF_MODES, height_m=height) if wait else None
    _send(cmd, "takeoff", vehicle, endpoint, timeout, action, wait_timeout, every)


@app.command()
def land(
    wait: bool = WaitOption,
    wait_timeout: float | None = WaitTimeoutOption,
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Land where the vehicle is; --wait until it is down and disarmed."""
    action = Land("land", LAND_MODES, ends_disarmed=True) if wait else None
    _send(commands.land_command(), "land", vehicle, endpoint, timeout, action, wait_timeout, every)


@app.command()
def hold(
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Hold position (PX4's Hold / auto:loiter)."""
    _send(commands.hold_command(), "hold", vehicle, endpoint, timeout, every=every)


@app.command()
def rtl(
    wait: bool = WaitOption,
    wait_timeout: float | None = WaitTimeoutOption,
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Return to home and land; --wait until it is down at home and disarmed."""
    action = Return("rtl", RETURN_MODES, ends_disarmed=True) if wait else None
    _send(commands.return_command(), "rtl", vehicle, endpoint, timeout, action, wait_timeout, every)


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
    wait_timeout: float | None = WaitTimeoutOption,
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

    action = Goto("goto", GOTO_MODES, target=target, speed=speed_ms) if wait else None
    _send(cmd, "goto", vehicle, endpoint, timeout, action, wait_timeout)


@app.command()
def mode(
    name: str = typer.Argument(..., help="PX4 mode name: manual, stabilized, acro, altctl, posctl, auto:loiter..."),
    timeout: float = TimeoutOption,
    every: bool = AllOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Switch flight mode (DO_SET_MODE with PX4's custom mode, as QGroundControl sends it)."""
    try:
        nav_state = nav_state_from_name(name)
    except ValueError as e:
        fail(f"{e}; nothing sent", code=2)
    _send(commands.set_mode_command(name), f"mode {MODES[nav_state].name}", vehicle, endpoint, timeout, every=every)


def _vehicle_home(link: _Link) -> tuple[GeoPoint | None, str]:
    """The vehicle's home from ``home_position``; failing that, where it is (``vehicle_local_position``)."""
    deadline = time.monotonic() + HOME_WAIT_S
    while time.monotonic() < deadline:
        link.poll()
        home = link.latest.get("home_position")
        if home is not None and home.valid_hpos and math.isfinite(home.lat) and math.isfinite(home.lon):
            return GeoPoint(home.lat, home.lon, home.alt), "the vehicle's home"
        time.sleep(POLL_S)
    lpos = link.vehicle.position
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
    try:
        publisher.publish(mission_message(mission, home, ident))
    except MessageTooLarge as e:
        fail(f"mission refused: {e}; nothing sent", code=2)
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


@app.command("mission")
def mission_(
    file: Path = typer.Argument(
        ...,
        help="QGroundControl .plan, QGC WPL 110 or a simple waypoint list: a path, or the name of a shipped mission "
        "(box, plane_rectangle)",
    ),
    no_start: bool = typer.Option(False, "--no-start", help="Upload only; do not start the mission"),
    first: int = typer.Option(0, "--first", help="Item to start at (−1: the current one)"),
    wait: bool = WaitOption,
    wait_timeout: float | None = WaitTimeoutOption,
    timeout: float = TimeoutOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Upload a mission (global positions placed about the vehicle's home) and start it."""
    try:
        file = find_mission(file)
    except FileNotFoundError as e:
        fail(str(e), code=2)
    check_may_command(endpoint)
    with connect(vehicle, endpoint) as node:
        link = _Link(node, timeout, ("mission_result", *WATCHED))
        home, origin = _vehicle_home(link)
        try:
            mission = load_mission(file, home)
        except MissionError as e:
            fail(str(e), code=2)
        too_many = too_many_items(len(mission))
        if too_many:
            fail(f"{file}: mission refused: {too_many}; nothing sent", code=2)
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
            action = MissionRun(
                "mission", MISSION_MODES, mission=mission, mission_id=result.mission_id, started_us=start.timestamp
            )
            link.follow(action, start, wait_timeout)
