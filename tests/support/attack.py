"""An attacker on a running stack's bus, as a process of its own:

    python -m tests.support.attack KIND SECONDS [--as MODULE] [--watch SECONDS]

publishes well-formed messages for SECONDS of wall time while it watches where the simulated vehicle truly is
(``sim_groundtruth``), then goes on watching as long again (or ``--watch``), and prints one JSON line: the
largest horizontal and vertical distance from where the vehicle was when the attack began, how many messages
it sent, whether a failsafe was seen, the last mode and arming state, and the vehicle's warnings meanwhile.

KIND is ``none`` (watch only), ``attitude`` (``vehicle_attitude`` rolled 30°, at 200 Hz: the estimate a
controller would fight), ``position`` (``vehicle_local_position`` 10 m higher than truth, at 100 Hz),
``nonfinite`` (NaN and infinity in every float field of every topic that has one, each topic in turn, as
fast as it goes) or ``nonfinite-states`` (on states and sensors only, in each field a value it never means:
NaN where it starts finite, infinity where it starts NaN, which means "unknown" there).
``--as MODULE`` sends with that module's publisher id, as a process pretending to be it would.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Iterator
from typing import Any

import msgspec

from stack.bus.node import Node, stable_publisher_id
from stack.cli.common import find_stack
from stack.msg.estimation import VehicleAttitude, VehicleLocalPosition
from stack.msg.registry import TOPICS
from stack.msg.simulation import SimGroundtruth
from stack.msg.system import MavlinkLog

ROLLED_30_DEG = (0.9659, 0.2588, 0.0, 0.0)


def forged(kind: str) -> Iterator[tuple[str, Any, float]]:
    """(topic, message, seconds until the next) forever."""
    if kind == "attitude":
        while True:
            yield "vehicle_attitude", VehicleAttitude(q=ROLLED_30_DEG), 1 / 200
    if kind == "position":
        while True:
            yield "vehicle_local_position", VehicleLocalPosition(xy_valid=True, z_valid=True, z=-10.0), 1 / 100
    if kind == "none":
        return
    if kind in ("nonfinite", "nonfinite-states"):
        values = (math.nan, math.inf, -math.inf)
        topics = [
            (name, topic.type)
            for name, topic in TOPICS.items()
            if _floats(topic.type) and (kind == "nonfinite" or not topic.type.NAN_MEANS_NOT_CONTROLLED)
        ]
        n = 0
        while True:
            for topic, cls in topics:
                n += 1
                value = values[n % 3] if kind == "nonfinite" else None
                yield topic, _filled(cls, value), 0.0
    raise SystemExit(f"unknown attack {kind!r}")


def _floats(cls: type) -> list[str]:
    """The fields of ``cls`` that are a float or a tuple of floats."""
    names = []
    for f in msgspec.structs.fields(cls):
        default = f.default if f.default is not msgspec.NODEFAULT else None
        if isinstance(default, float) or (
            isinstance(default, tuple) and default and all(isinstance(v, float) for v in default)
        ):
            names.append(f.name)
    return names


def _filled(cls: type, value: float | None) -> Any:
    """A ``cls`` message with ``value`` in every float field and every float of its fixed tuples; with None, a
    value the field never means: NaN where it starts finite or infinite, infinity where it starts NaN."""
    defaults = cls()

    def garbage(default: float) -> float:
        return value if value is not None else math.inf if math.isnan(default) else math.nan

    return cls(
        **{
            name: tuple(garbage(v) for v in d) if isinstance(d := getattr(defaults, name), tuple) else garbage(d)
            for name in _floats(cls)
        }
    )


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("kind", choices=("none", "attitude", "position", "nonfinite", "nonfinite-states"))
    parser.add_argument("seconds", type=float)
    parser.add_argument("--as", dest="as_module", default="")
    parser.add_argument("--watch", type=float, default=None, help="seconds to watch after (default: SECONDS)")
    args = parser.parse_args()
    vehicle, bus = find_stack(None, None)
    # It watches under a name of its own: a module's name would tell the fast path its reads are served there.
    with Node(bus, vehicle, "attacker", stable_id=False) as node, Node(
        bus, vehicle, args.as_module or "attacker", stable_id=bool(args.as_module)
    ) as sender:
        truth = node.subscriber("sim_groundtruth", keep_last=True, announce=True)
        status = node.subscriber("vehicle_status", keep_last=True, announce=True)
        said = node.subscriber("mavlink_log", callback=True, announce=True)
        seen = {"failsafe": False, "nav_state": -1, "armed": False, "said": []}
        publishers: dict[str, Any] = {}
        simulator = stable_publisher_id(vehicle, "simulator")  # not the forgeries this process sends
        start = None
        while start is None:
            item = truth.recv()
            start = item.msg.position if item.publisher == simulator else None
        worst = [0.0, 0.0]

        def look() -> None:
            while (item := truth.poll()) is not None:
                if item.publisher != simulator:
                    continue
                gt: SimGroundtruth = item.msg
                north, east, down = (a - b for a, b in zip(gt.position, start, strict=True))
                worst[0] = max(worst[0], math.hypot(north, east))
                worst[1] = max(worst[1], abs(down))
            while (item := status.poll()) is not None:
                seen["failsafe"] |= item.msg.failsafe
                seen["nav_state"], seen["armed"] = item.msg.nav_state, item.msg.arming_state == 2
            while (item := said.poll()) is not None:
                if item.msg.severity <= MavlinkLog.SEVERITY_WARNING:
                    seen["said"].append(item.msg.text)

        sent = 0
        began = time.monotonic()
        next_send = began
        for topic, msg, period in forged(args.kind):
            if time.monotonic() - began > args.seconds:
                break
            if topic not in publishers:
                publishers[topic] = sender.publisher(topic, announce=False)
            publishers[topic].publish(msg)
            sent += 1
            look()
            next_send += period
            if period:
                time.sleep(max(0.0, next_send - time.monotonic()))
        settle = time.monotonic() + (args.seconds if args.watch is None else args.watch)
        while time.monotonic() < settle:
            look()
            time.sleep(0.01)
        print(json.dumps({"sent": sent, "horizontal_m": worst[0], "vertical_m": worst[1], **seen}))


if __name__ == "__main__":
    main()
