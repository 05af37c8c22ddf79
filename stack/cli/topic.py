"""``stack topic``: list, echo, hz, pub, info — PX4's ``uorb top`` and ``listener`` for a running stack."""

from __future__ import annotations

import itertools
import json
import math
import signal
import statistics
import time
from dataclasses import dataclass

import msgspec
import typer
import zenoh

from stack.bus import keys
from stack.bus.access import OPEN_TO_TOOLS, tool_may_publish
from stack.bus.graph import read_graph
from stack.bus.node import Node
from stack.bus.supervisors import vehicle_status
from stack.bus.topics import HEADER, Received
from stack.cli.common import (
    EndpointOption,
    InstanceOption,
    JsonOption,
    VehicleOption,
    command_group,
    connect,
    fail,
    format_value,
    number,
    print_table,
    to_jsonable,
    wait_until_sent,
)
from stack.cli.inbox import Inbox
from stack.cli.message_json import as_dict, parse_field_paths, parse_message, pick
from stack.msg.base import Message
from stack.msg.registry import TOPICS, UnknownTopic, fingerprint, message_type, schema_text

app = command_group(help="Inspect and publish topics (like PX4's listener and uorb top).", no_args_is_help=True)


def _topic_type(topic: str) -> type[Message]:
    try:
        return message_type(topic)
    except UnknownTopic as e:
        fail(str(e))


@dataclass
class _Traffic:
    count: int = 0
    size: int = 0


def _measure(session: zenoh.Session, vehicle: str, window: float) -> dict[tuple[str, int], _Traffic]:
    traffic: dict[tuple[str, int], _Traffic] = {}

    def on_sample(sample: zenoh.Sample) -> None:
        parsed = keys.parse_topic_key(str(sample.key_expr))
        if parsed is None:
            return
        t = traffic.setdefault((parsed[1], parsed[2]), _Traffic())
        t.count += 1
        t.size = len(sample.payload)

    sub = session.declare_subscriber(keys.all_topics(vehicle), on_sample)
    time.sleep(window)
    sub.undeclare()
    return traffic


def _ask_for(node: Node, topics: list[tuple[str, int]]) -> None:
    """Subscribe in the topic graph, so that a fast-path run puts these topics on Zenoh."""
    for topic, instance in topics:
        node.announce("sub", topic, instance)
    wait_until_sent(node, topics)


@app.command("list")
def list_topics(
    window: float = typer.Option(1.0, callback=number(above=0), help="Seconds to measure rates over"),
    all_: bool = typer.Option(False, "--all", "-a", help="Also list catalogue topics nobody uses"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """Topics with type, instance, publishers, subscribers, rate and message size (like `uorb top -1`)."""
    with connect(vehicle, endpoint) as node:
        graph = read_graph(node.session, node.vehicle)
        _ask_for(node, [key for key, g in graph.items() if g.publishers])
        traffic = _measure(node.session, node.vehicle, window)
    rows = []
    names = set(graph) | set(traffic)
    if all_:
        names |= {(t, 0) for t in TOPICS}
    for topic, inst in sorted(names):
        g = graph.get((topic, inst))
        tr = traffic.get((topic, inst), _Traffic())
        type_name = g.type_name if g else (TOPICS[topic].type.__name__ if topic in TOPICS else "?")
        rows.append(
            {
                "topic": topic,
                "type": type_name,
                "instance": inst,
                "publishers": g.publishers if g else [],
                "subscribers": g.subscribers if g else [],
                "rate_hz": tr.count / window,
                "size_bytes": tr.size,
            }
        )
    if as_json:
        typer.echo(json.dumps(rows))
        return
    total = sum(r["rate_hz"] for r in rows)
    typer.echo(f"topics: {len(rows)}, total publications: {total:.0f}/s (measured over {window:g} s)")
    print_table(
        ("TOPIC", "TYPE", "INST", "#PUB", "#SUB", "RATE", "SIZE", "PUBLISHERS"),
        [
            (
                r["topic"],
                r["type"],
                r["instance"],
                len(r["publishers"]),
                len(r["subscribers"]),
                f"{r['rate_hz']:.1f}",
                r["size_bytes"],
                ",".join(r["publishers"]),
            )
            for r in rows
        ],
    )


ECHO_QUEUE = 1000
"""Messages kept between the subscriber and the printer by default (a few seconds of a fast topic)."""
HZ_WINDOW = 10_000
"""The intervals `topic hz` averages by default, as ``ros2 topic hz``: a window of a fraction of a second (it was
100 intervals, 0.4 s at 250 Hz) read a topic's rate 30 % low when the reader itself waited for a CPU."""


def _subscribe(node: Node, topic: str, instance: int, capacity: int) -> tuple[zenoh.Subscriber, Inbox[Received]]:
    msg_type = _topic_type(topic)
    node.announce("sub", topic, instance)
    wait_until_sent(node, [(topic, instance)])
    decoder = msgspec.msgpack.Decoder(msg_type)
    expected = fingerprint(msg_type)
    inbox: Inbox[Received] = Inbox(capacity)
    warned = []

    def on_sample(sample: zenoh.Sample) -> None:
        att = sample.attachment
        if att is None or len(att) != HEADER.size:
            return
        fp, pub, seq, index, t, _flags, _run = HEADER.unpack(att.to_bytes())
        if fp != expected:
            if not warned:
                warned.append(1)
                typer.echo(
                    f"warning: {topic} publisher {pub:08x} uses schema {fp:016x}, this build has {expected:016x};"
                    " its messages are not shown",
                    err=True,
                )
            return
        try:
            inbox.put(Received(t, pub, seq, decoder.decode(sample.payload.to_bytes()), index))
        except msgspec.DecodeError as e:
            typer.echo(f"warning: malformed {topic} message dropped: {e}", err=True)

    return node.session.declare_subscriber(keys.topic_key(node.vehicle, topic, instance), on_sample), inbox


@app.command()
def echo(
    topic: str,
    count: int = typer.Option(0, "-n", "--count", min=0, help="Print N messages then exit (0: until Ctrl-C)"),
    instance: int = InstanceOption,
    field: list[str] = typer.Option(
        [],
        "--field",
        "-f",
        help="Print only this field; repeat or separate with commas for several; dotted paths and list "
        "indexes reach into nested fields (q.0, items.1.north)",
    ),
    rate: float = typer.Option(
        0.0, "--rate", "-r", callback=number(0), help="At most this many messages a second, the newest (0: all)"
    ),
    capacity: int = typer.Option(
        ECHO_QUEUE, "--queue", min=1, help="Messages kept waiting for a slow reader (beyond it the oldest are dropped)"
    ),
    timeout: float = typer.Option(
        5.0, callback=number(above=0), help="Give up after this many seconds without a message"
    ),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """Print messages of a topic as they arrive (like PX4's `listener`). Behind a slow reader the oldest
    waiting messages are dropped, and the drops are counted on stderr."""
    msg_type = _topic_type(topic)
    paths = parse_field_paths(field)
    fields = msg_type.__struct_fields__
    for path in paths:
        if path.split(".")[0] not in fields:
            fail(f"{msg_type.__name__} has no field '{path.split('.')[0]}' (fields: {', '.join(fields)})")
    period = 1.0 / rate if rate > 0 else 0.0
    with connect(vehicle, endpoint) as node:
        # With --rate only the newest waiting message matters: the inbox keeps just that one.
        sub, inbox = _subscribe(node, topic, instance, 1 if period else capacity)
        shown = reported = 0
        try:
            next_time = time.monotonic()
            while count == 0 or shown < count:
                time.sleep(max(0.0, next_time - time.monotonic()))
                item = inbox.get(timeout)
                if item is None:
                    fail(f"waited {timeout:g} s without a message on {topic} (instance {instance})")
                next_time = time.monotonic() + period
                shown += 1
                if not period and inbox.dropped > reported:
                    typer.echo(f"[{inbox.dropped - reported} {topic} messages dropped: output too slow]", err=True)
                    reported = inbox.dropped
                _print_message(topic, instance, item.msg, paths, as_json, shown)
        finally:
            sub.undeclare()
            if not period and inbox.dropped:
                typer.echo(f"{topic}: {shown} shown, {inbox.dropped} dropped (output too slow)", err=True)


def _print_message(topic: str, instance: int, msg: Message, paths: list[str], as_json: bool, n: int) -> None:
    data = as_dict(msg)
    if paths:
        try:
            picked = {path: pick(data, path) for path in paths}
        except KeyError as e:
            fail(f"{type(msg).__name__}: {e.args[0]}")
        if as_json:
            only = picked[paths[0]] if len(paths) == 1 else picked
            typer.echo(json.dumps(to_jsonable(only)))
        elif len(paths) == 1:
            typer.echo(format_value(picked[paths[0]]))
        else:
            typer.echo("  ".join(f"{path}: {format_value(value)}" for path, value in picked.items()))
        return
    if as_json:
        typer.echo(json.dumps(to_jsonable(data)))
        return
    typer.echo(f"TOPIC: {topic} instance {instance} #{n}  [{type(msg).__name__}]")
    for name, value in data.items():
        extra = f"  ({value / 1e6:.6f} s)" if name.startswith("timestamp") and isinstance(value, int) else ""
        typer.echo(f"    {name}: {format_value(value)}{extra}")


@app.command()
def hz(
    topic: str,
    window: int = typer.Option(HZ_WINDOW, min=1, help="Number of most recent intervals the statistics use"),
    duration: float = typer.Option(0.0, callback=number(0), help="Stop after this many seconds (0: until Ctrl-C)"),
    instance: int = InstanceOption,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """Publication rate of a topic, with min/max/std of the intervals, printed every second."""
    _topic_type(topic)
    with connect(vehicle, endpoint) as node:
        sub, inbox = _subscribe(node, topic, instance, ECHO_QUEUE)
        arrivals: list[float] = []
        stamps: list[int] = []
        start = time.monotonic()
        next_print = start + 1.0
        try:
            while duration == 0 or time.monotonic() - start < duration:
                if (item := inbox.get(timeout=0.05)) is not None:
                    arrivals.append(time.monotonic())
                    stamps.append(item.msg.timestamp)
                    del arrivals[: -window - 1], stamps[: -window - 1]
                if time.monotonic() >= next_print:
                    next_print += 1.0
                    _print_rate(topic, arrivals, stamps, as_json)
        finally:
            sub.undeclare()


def _print_rate(topic: str, arrivals: list[float], stamps: list[int], as_json: bool) -> None:
    if len(arrivals) < 2:
        typer.echo(json.dumps({"topic": topic, "rate_hz": 0.0}) if as_json else f"{topic}: no new messages")
        return
    dts = [b - a for a, b in itertools.pairwise(arrivals)]
    span = arrivals[-1] - arrivals[0]
    rate = len(dts) / span if span > 0 else math.inf
    stamp_span = (stamps[-1] - stamps[0]) / 1e6
    msg_rate = len(dts) / stamp_span if stamp_span > 0 else math.nan
    stats = {
        "topic": topic,
        "rate_hz": rate,
        "rate_by_timestamp_hz": msg_rate,
        "min_s": min(dts),
        "max_s": max(dts),
        "std_s": statistics.pstdev(dts),
        "window": len(dts),
    }
    if as_json:
        typer.echo(json.dumps(to_jsonable(stats)))
    else:
        typer.echo(
            f"{topic}: average rate {rate:.2f} Hz (by message timestamps {msg_rate:.2f} Hz)  "
            f"min {min(dts) * 1e3:.2f} ms  max {max(dts) * 1e3:.2f} ms  std {stats['std_s'] * 1e3:.2f} ms  "
            f"window {len(dts)}"
        )


@app.command(context_settings={"ignore_unknown_options": True})  # values may be a negative number
def pub(
    topic: str,
    values: str = typer.Argument(..., help="Field values as JSON, e.g. '{\"roll\": 0.1}'"),
    rate: float = typer.Option(
        0.0, "--rate", "-r", callback=number(0), help="Publish repeatedly at this rate [Hz] until Ctrl-C"
    ),
    count: int = typer.Option(0, "--count", "-n", min=0, help="With --rate: stop after N messages"),
    instance: int = InstanceOption,
    wait: float = typer.Option(1.0, callback=number(0), help="Seconds to wait for a subscriber before publishing"),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Publish a message, checked against the topic's schema (a wrong field or type publishes nothing)."""
    _topic_type(topic)
    try:
        template = parse_message(topic, values)
    except ValueError as e:
        fail(str(e), code=2)
    with connect(vehicle, endpoint) as node:
        status = vehicle_status(node.session, node.vehicle)
        if not tool_may_publish(topic, status.get("open_topics", ()) if status else ()):
            owners = read_graph(node.session, node.vehicle).get((topic, instance))
            by = f" (published by {', '.join(owners.publishers)})" if owners and owners.publishers else ""
            fail(
                f"{topic} is a topic of the vehicle's modules{by}: a tool may publish only commands, sticks, "
                f"missions and Offboard setpoints ({', '.join(sorted(OPEN_TO_TOOLS))}), or what the profile "
                "opens with [stack] open_topics",
                code=2,
            )
        publisher = node.publisher(topic, instance)
        deadline = time.monotonic() + wait
        while not publisher.matching() and time.monotonic() < deadline:
            time.sleep(0.01)
        if not publisher.matching():
            typer.echo(f"warning: no subscriber for {topic} (instance {instance})", err=True)
        sent = 0
        period = 1.0 / rate if rate > 0 else 0.0
        next_time = time.monotonic()
        # Ctrl-C ends a --rate stream, what was sent is said below. A flag, not an exception: SIGINT may land
        # while Zenoh publishes, and an exception raised there would leave its session unable to close.
        interrupted: list[int] = []
        previous = signal.signal(signal.SIGINT, lambda signum, frame: interrupted.append(signum))
        if rate > 0:
            until = f"{count} message{'s' if count != 1 else ''}" if count else "until Ctrl-C"
            typer.echo(f"publishing {type(template).__name__} on {topic} (instance {instance}) at {rate:g} Hz, {until}")
        try:
            while not interrupted:
                publisher.publish(msgspec.structs.replace(template))
                sent += 1
                if rate <= 0 or (count and sent >= count):
                    break
                next_time += period
                time.sleep(max(0.0, next_time - time.monotonic()))
        finally:
            signal.signal(signal.SIGINT, previous)
        time.sleep(0.1)  # let Zenoh flush before the session closes
    typer.echo(f"published {sent} message{'s' if sent != 1 else ''} on {topic}")


def _type_name(t: object) -> str:
    return t.__name__ if isinstance(t, type) else str(t).replace("typing.", "")


def _default(field: msgspec.structs.FieldInfo) -> object:
    """A field's default as JSON: made by its factory where it has one (a list, a nested message); None if required."""
    if field.default is not msgspec.NODEFAULT:
        return to_jsonable(field.default)
    if field.default_factory is not msgspec.NODEFAULT:
        return to_jsonable(field.default_factory())
    return None


def schema_rows(msg_type: type[Message]) -> list[dict[str, object]]:
    """A message's fields as JSON: name, type and default."""
    return [
        {"name": f.name, "type": _type_name(f.type), "default": _default(f)} for f in msgspec.structs.fields(msg_type)
    ]


@app.command()
def info(
    topic: str,
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
    as_json: bool = JsonOption,
) -> None:
    """A topic's type, schema (fields, types, defaults), fingerprint, publishers and subscribers."""
    msg_type = _topic_type(topic)
    schema = schema_rows(msg_type)
    result: dict[str, object] = {
        "topic": topic,
        "type": msg_type.__name__,
        "fingerprint": f"{fingerprint(msg_type):016x}",
        "doc": (msg_type.__doc__ or "").strip(),
        "fields": schema,
        "schema": schema_text(msg_type),
    }
    with connect(vehicle, endpoint) as node:
        graph = read_graph(node.session, node.vehicle)
    instances = sorted(inst for (t, inst) in graph if t == topic)
    result["instances"] = [
        {
            "instance": inst,
            "publishers": graph[(topic, inst)].publishers,
            "subscribers": graph[(topic, inst)].subscribers,
            "fingerprints": sorted(graph[(topic, inst)].fingerprints),
        }
        for inst in instances
    ]
    if as_json:
        typer.echo(json.dumps(result))
        return
    typer.echo(f"{topic}: {result['type']}  fingerprint {result['fingerprint']}")
    if result["doc"]:
        typer.echo(f"  {result['doc']}")
    for inst in result["instances"]:
        typer.echo(f"  instance {inst['instance']}: publishers {inst['publishers']}, subscribers {inst['subscribers']}")
        if len(inst["fingerprints"]) > 1 or result["fingerprint"] not in inst["fingerprints"]:
            typer.echo(f"    WARNING: schema fingerprints on the bus: {inst['fingerprints']}")
    print_table(("FIELD", "TYPE", "DEFAULT"), [(f["name"], f["type"], f["default"]) for f in schema])
