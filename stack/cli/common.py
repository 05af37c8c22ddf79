"""What every CLI command needs: finding the running stack, opening a session, printing tables."""

from __future__ import annotations

import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any, NoReturn

import msgspec
import typer
import zenoh

from stack.bus import keys
from stack.bus.alive import vehicles_alive
from stack.bus.config import BusConfig
from stack.bus.node import Node, open_session
from stack.bus.supervisors import outside_ready
from stack.supervisor import state as run_state
from stack.supervisor.profile import LOCKSTEP_TRANSPORTS, Profile, ProfileError


def command_group(**settings: object) -> typer.Typer:
    """A command group with plain help screens, as Click prints them: an option's value placeholder only where
    it takes a value (no ``<bool>`` beside a flag), no boxes."""
    return typer.Typer(rich_markup_mode=None, **settings)  # type: ignore[arg-type]


def name_value_placeholders(command: Any) -> None:
    """Each value's placeholder in the help is its name (``--seed SEED``), as Click and argparse print them, not its
    Python type (``<int>``)."""
    for param in command.params:
        takes_value = not getattr(param, "is_flag", False) and not getattr(param, "count", False)
        if param.metavar is None and takes_value and param.name:
            param.metavar = param.name.upper()
            if param.param_type_name == "argument":  # Typer prints an argument's type after its name
                param.display_type_rich = lambda ctx: None
    for sub in getattr(command, "commands", {}).values():
        name_value_placeholders(sub)


def number(
    low: float | None = None, high: float | None = None, *, above: float | None = None
) -> Callable[[float | None], float | None]:
    """An option's check (``callback=``): a finite number, at least ``low`` (or above ``above``) and at most
    ``high``. Anything else is a usage error naming the option before the command does anything (Click's ranges
    let NaN and infinity through); an option left out (None) passes."""
    if high is None:
        text = f"x>={low:g}" if low is not None else f"x>{above:g}" if above is not None else ""
    else:
        floor = f"{low:g}<=" if low is not None else f"{above:g}<" if above is not None else ""
        text = f"{floor}x<={high:g}"

    def check(value: float | None) -> float | None:
        if value is None:
            return None
        if (
            not math.isfinite(value)
            or (low is not None and value < low)
            or (above is not None and value <= above)
            or (high is not None and value > high)
        ):
            raise typer.BadParameter(f"{value:g} is not a finite number{' in the range ' + text if text else ''}.")
        return value

    return check


def output_file(value: str | Path | None) -> str | Path | None:
    """An option's check (``callback=``) for a file the command will write: that it can be written, tried before
    the command does anything (a flight flown, a stack started), so that a wrong path is not found at the end. A
    file made by the try is removed; an option left out (None or "") passes."""
    if not value:
        return value
    path = Path(value)
    existed = path.exists()
    try:
        with path.open("ab"):
            pass
    except OSError as e:
        raise typer.BadParameter(f"cannot write {path}: {e.strerror or e}") from None
    if not existed:
        path.unlink()
    return value


def output_directory(value: Path | None) -> Path | None:
    """An option's check (``callback=``) for a directory the command will write files into, made if missing:
    that it can be, tried (a file made and removed in it, or in the nearest directory above it that exists)
    before the command does anything."""
    if value is None:
        return None
    existing = next((p for p in (value, *value.absolute().parents) if p.exists()), Path("/"))
    if existing == value and not value.is_dir():
        raise typer.BadParameter(f"{value} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as e:
        raise typer.BadParameter(f"cannot write in {existing}: {e.strerror or e}") from None
    return value


VehicleOption = typer.Option(
    None,
    "--vehicle",
    "-v",
    help="The stack: its vehicle, or a flight's <vehicle>-fly-<pid> (default: the `stack up` one, else the flight)",
)
EndpointOption = typer.Option(
    None, "--endpoint", "-e", envvar="STACK_ENDPOINT", help="Zenoh endpoint of the stack (default: from stack up)"
)
JsonOption = typer.Option(False, "--json", help="Machine-readable JSON output")
InstanceOption = typer.Option(0, "--instance", "-i", min=0, help="The topic's instance (PX4's multi-instance index)")
TransportOption = typer.Option(
    None,
    "--lockstep-transport",
    help="How lockstep messages travel, overriding the profile: shm (same-host shared memory) or zenoh",
)


def fail(message: str, code: int = 1) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


InsecureOption = typer.Option(
    False, "--insecure", help="Listen beyond this machine without a keystore (plain links: anyone on them gets in)"
)
KeystoreOption = typer.Option(
    None, "--keystore", help="The keystore of the links between hosts (the profile's [security] keystore otherwise)"
)


def check_exposure(prof: Profile, host: str | None, insecure: bool, keystore: Path | None = None) -> None:
    """With ``keystore``, the profile's links between hosts on mutual TLS from it (its identity for ``host`` named
    now if missing); then refuse (exit 2, saying why) a stack that would listen beyond this machine over plain links
    unless ``insecure`` (stack.security.exposure)."""
    from stack.security.exposure import exposure_problem

    if keystore is not None:
        if not (keystore / "ca.pem").exists():
            fail(f"--keystore: no keystore at {keystore} (make one with `stack keys init {keystore}`)", code=2)
        prof.keystore = keystore.expanduser().resolve()
        if host is not None:
            try:
                prof.host_tls(host)
            except ProfileError as e:
                fail(str(e), code=2)

    what = f"host {host} of {prof.path}" if host is not None else str(prof.path)
    problem = exposure_problem(what, prof.listen_endpoints(host), insecure)
    if problem:
        fail(problem, code=2)


OUTSIDE_WAIT_S = 2.0


def choose_transport(prof: Profile, transport: str | None) -> None:
    if transport is None:
        return
    if transport not in LOCKSTEP_TRANSPORTS:
        fail(f"--lockstep-transport must be one of {', '.join(LOCKSTEP_TRANSPORTS)}, not '{transport}'", code=2)
    prof.lockstep_transport = transport


def find_stack(vehicle: str | None, endpoint: str | None) -> tuple[str, BusConfig]:
    """The vehicle and bus settings to reach a running stack (with ``endpoint``, the vehicle is checked on the bus
    once connected: see :func:`vehicle_on_bus`)."""
    if vehicle is not None:
        try:
            keys.check_name("vehicle", vehicle)
        except ValueError as e:
            fail(str(e), code=2)
    if endpoint:
        return vehicle or "", endpoint_bus(endpoint)
    stacks = run_state.addressed_stacks(vehicle)
    if not stacks:
        which = f" named '{vehicle}'" if vehicle else ""
        fail(f"no running stack found{which} (start one with `stack up`, or pass --endpoint)")
    if len(stacks) > 1:
        names = ", ".join(run_state.stack_name(s) for s in stacks)
        fail(f"several stacks are running ({names}): choose one with --vehicle")
    found = stacks[0]
    bus = BusConfig.from_json(json.dumps(found["bus"]))
    return str(found["vehicle"]), BusConfig(
        mode="client", connect=(str(found["endpoint"]),), listen=(), low_latency=bus.low_latency, lease_ms=bus.lease_ms
    )


@contextmanager
def connect(vehicle: str | None, endpoint: str | None, name: str = "cli") -> Iterator[Node]:
    found, bus = find_stack(vehicle, endpoint)
    tool = f"{name}-{os.getpid()}"  # unique in the topic graph, where each tool's subscriptions are its own
    session = open_bus(bus, tool)
    try:
        if endpoint:
            found = vehicle_on_bus(session, vehicle, endpoint)
        with Node(bus, found, tool, stable_id=False, session=session) as node:
            yield node
    finally:
        session.close()


def bus_configs(endpoint: str | None) -> list[BusConfig]:
    """The buses a command on every vehicle addresses: ``endpoint``'s, else those of the stacks a command naming no
    stack addresses (the `stack up` ones, else the flights)."""
    if endpoint:
        return [endpoint_bus(endpoint)]
    endpoints = sorted({str(s["endpoint"]) for s in run_state.addressed_stacks(None)})
    if not endpoints:
        fail("no running stack found (start one with `stack up`, or pass --endpoint)")
    return [BusConfig(mode="client", connect=(e,), listen=()) for e in endpoints]


@contextmanager
def connect_all(endpoint: str | None, name: str = "cli") -> Iterator[list[Node]]:
    """A node for every vehicle alive on the buses of :func:`bus_configs` (each vehicle once, by name)."""
    tool = f"{name}-{os.getpid()}"
    with ExitStack() as stack:
        nodes: dict[str, Node] = {}
        for bus in bus_configs(endpoint):
            session = open_bus(bus, tool)
            stack.callback(session.close)
            for vehicle in sorted(vehicles_alive(session) - set(nodes)):
                nodes[vehicle] = stack.enter_context(Node(bus, vehicle, tool, stable_id=False, session=session))
        if not nodes:
            fail("no vehicle on the bus (no module alive there)")
        yield [nodes[v] for v in sorted(nodes)]


KEYSTORE_ENV, IDENTITY_ENV = "STACK_KEYSTORE", "STACK_IDENTITY"


def endpoint_bus(endpoint: str) -> BusConfig:
    """A tool's bus to the router at ``endpoint``: over mutual TLS (``tls/``) with the identity STACK_IDENTITY of
    the keystore STACK_KEYSTORE (``stack --keystore DIR --identity NAME``), which must be given."""
    if not endpoint.startswith("tls/"):
        return BusConfig(mode="client", connect=(endpoint,), listen=())
    keystore, identity = os.environ.get(KEYSTORE_ENV, ""), os.environ.get(IDENTITY_ENV, "")
    if not keystore or not identity:
        fail(
            f"{endpoint} admits only identities of its keystore: give `stack --keystore DIR --identity NAME ...` "
            f"(or set {KEYSTORE_ENV} and {IDENTITY_ENV})",
            code=2,
        )
    from stack.security.keystore import KeystoreError
    from stack.security.tls import tls_files

    try:
        tls = tls_files(Path(keystore).expanduser(), identity)
    except KeystoreError as e:
        fail(f"identity {identity}: {e}", code=2)
    return BusConfig(mode="client", connect=(endpoint,), listen=(), tls=tls)


def check_may_command(endpoint: str | None) -> None:
    """Refuse (exit 2) to command over mutual TLS as an identity whose role may not: its router would drop the
    command without a word to the sender (stack.security.acl)."""
    if not endpoint or not endpoint.startswith("tls/"):
        return
    endpoint_bus(endpoint)  # the identity named and valid, or one clear line
    from stack.security.keystore import read_identity

    identity = read_identity(Path(os.environ[KEYSTORE_ENV]).expanduser(), os.environ[IDENTITY_ENV])
    if identity.role not in ("operator", "host"):
        fail(
            f"identity {identity.name} is an {identity.role}: it may read the vehicle, not command it; nothing sent",
            code=2,
        )


def open_bus(bus: BusConfig, tool: str) -> zenoh.Session:
    try:
        return open_session(bus, tool)
    except zenoh.ZError as e:
        where = ", ".join(bus.connect)
        if bus.tls:
            who = Path(bus.tls["certificate"]).stem
            fail(f"the stack at {where} did not admit identity {who} (not of its keystore?), or it is not running")
        fail(f"cannot reach the stack at {where} ({str(e).split(' at ')[0].strip()}); is it running?")


def vehicle_on_bus(session: zenoh.Session, vehicle: str | None, endpoint: str) -> str:
    """``vehicle`` if a module of it is alive on the bus, or the only vehicle there when none is named; else one
    clear error naming the vehicles there."""
    there = sorted(vehicles_alive(session))
    if vehicle is None and len(there) == 1:
        return there[0]
    if vehicle is not None and vehicle in there:
        return vehicle
    if not there:
        fail(f"no vehicle on the bus at {endpoint} (no module alive there)")
    if vehicle is None:
        fail(f"several vehicles on the bus at {endpoint} ({', '.join(there)}): choose one with --vehicle")
    fail(f"no vehicle '{vehicle}' on the bus at {endpoint} (there: {', '.join(there)})")


def wait_until_sent(node: Node, topics: Iterable[tuple[str, int]], timeout: float = OUTSIDE_WAIT_S) -> None:
    """Wait until the stack puts ``topics``, which this tool has subscribed to (and announced in the topic
    graph), on Zenoh: a fast-path run sends a topic over Zenoh only while something outside subscribes."""
    wanted = {f"{topic}/{instance}" for topic, instance in topics}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if outside_ready(node.session, node.vehicle, wanted):
            return
        time.sleep(0.01)


def to_jsonable(obj: object) -> object:
    """Builtins for JSON output; NaN and infinities become null (JSON has no NaN)."""
    return msgspec.json.decode(msgspec.json.encode(obj))


def format_value(value: object) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return f"{value:.6g}"
    if isinstance(value, tuple | list):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    return str(value)


def print_table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> None:
    cells = [[str(h) for h in headers]] + [[str(c) for c in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    for r in cells:
        sys.stdout.write("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() + "\n")
    sys.stdout.flush()
