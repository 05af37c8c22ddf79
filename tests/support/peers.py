"""Bus peers run as separate processes by the tests: ``python -m tests.support.peers MODE ...``.

- ``pub ENDPOINT N``: listens on ENDPOINT, waits for a subscriber, publishes N vehicle_command messages.
- ``sub ENDPOINT N OUT``: connects to ENDPOINT, receives N vehicle_command messages, writes them as JSON.
- ``rogue``: joins the running stack (found through STACK_HOME) and sends it bad samples on
  vehicle_command: malformed payloads, a foreign schema fingerprint, and samples without the stack header.
"""

from __future__ import annotations

import json
import sys
import time

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig
from stack.bus.node import Node
from stack.bus.topics import HEADER
from stack.cli.common import find_stack
from stack.msg.registry import fingerprint
from stack.msg.system import VehicleCommand


def publish(endpoint: str, n: int) -> None:
    with Node(BusConfig(listen=(endpoint,)), "t1", "test_publisher") as node:
        pub = node.publisher("vehicle_command")
        while not pub.matching():
            time.sleep(0.01)
        for i in range(n):
            pub.publish(VehicleCommand(command=400, param1=float(i)), now_us=i + 1)
        time.sleep(0.5)


def subscribe(endpoint: str, n: int, out: str) -> None:
    with Node(BusConfig(connect=(endpoint,)), "t1", "test_subscriber") as node:
        sub = node.subscriber("vehicle_command", capacity=n + 16)
        got = []
        while len(got) < n:
            t, pub, seq, msg, _ = sub.recv()
            got.append({"t": t, "publisher": pub, "seq": seq, "param1": msg.param1, "command": msg.command})
    with open(out, "w") as f:
        json.dump(got, f)


def rogue() -> None:
    vehicle, bus = find_stack(None, None)
    with zenoh.open(bus.zenoh_config("rogue")) as session:
        key = keys.topic_key(vehicle, "vehicle_command", 0)
        pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
        time.sleep(0.5)
        good_fp = fingerprint(VehicleCommand)
        for i in range(20):
            # The right header with a payload that is not a VehicleCommand.
            pub.put(b"\xc1\x00garbage", attachment=HEADER.pack(good_fp, 99, i, i + 1, 0, 0))
            # A well-formed message from a publisher built with another definition.
            pub.put(msgspec.msgpack.encode(VehicleCommand()), attachment=HEADER.pack(good_fp ^ 1, 99, i, i + 1, 0, 0))
            # No stack header at all.
            pub.put(msgspec.msgpack.encode(VehicleCommand()))
            time.sleep(0.01)
        time.sleep(0.5)
        pub.undeclare()


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "pub":
        publish(sys.argv[2], int(sys.argv[3]))
    elif mode == "sub":
        subscribe(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    elif mode == "rogue":
        rogue()
    else:
        sys.exit(f"unknown mode {mode}")
