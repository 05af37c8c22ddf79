"""Bus peers run as separate processes by the tests: ``python -m tests.support.peers MODE ...``.

- ``pub ENDPOINT N``: listens on ENDPOINT, waits for a subscriber, publishes N vehicle_command messages.
- ``sub ENDPOINT N OUT``: connects to ENDPOINT, receives N vehicle_command messages, writes them as JSON.
- ``rogue``: joins the running stack (found through STACK_HOME) and sends it bad samples on
  vehicle_command: malformed payloads, a foreign schema fingerprint, and samples without the stack header.
- ``attack MEMBER...``: joins the running stack and goes for its lockstep (the test chain's): garbage and
  forged messages on the lockstep's own keys (the tick keys of the named members), a sensor_gyro forged
  as the simulator's with a lockstep time 10^12 µs ahead, an outside sensor_gyro, and a flood of garbage on
  vehicle_rates_setpoint, a latest-value input of the chain.
- ``forge``: joins the running stack and declares and withdraws malformed alive tokens, five times each,
  then declares a well-formed one of a module ``forge_done`` (pid 4242) and leaves: the stack sees it come
  and go after all the malformed ones.
"""

from __future__ import annotations

import json
import sys
import time

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.config import BusConfig
from stack.bus.node import Node, stable_publisher_id
from stack.bus.topics import FLAG_LOCKSTEP_TIME, HEADER
from stack.cli.common import find_stack
from stack.msg.internal import LockstepAck, LockstepClock
from stack.msg.registry import fingerprint
from stack.msg.sensors import SensorGyro
from stack.msg.setpoints import VehicleRatesSetpoint
from stack.msg.system import VehicleCommand

# Zenoh has no flush: a session closed at once may drop what it still queues, so a peer lingers this long.
FLUSH_S = 0.5


def wait_matching(pub: zenoh.Publisher, timeout: float = 30.0) -> None:
    """Until the stack's subscribers of ``pub``'s key are known to this session (routes are in place)."""
    deadline = time.monotonic() + timeout
    while not pub.matching_status.matching:
        if time.monotonic() > deadline:
            sys.exit(f"no subscriber of {pub.key_expr} within {timeout:g} s")
        time.sleep(0.01)


def publish(endpoint: str, n: int) -> None:
    with Node(BusConfig(listen=(endpoint,)), "t1", "test_publisher") as node:
        pub = node.publisher("vehicle_command")
        while not pub.matching():
            time.sleep(0.01)
        for i in range(n):
            pub.publish(VehicleCommand(command=400, param1=float(i)), now_us=i + 1)
        time.sleep(FLUSH_S)


def subscribe(endpoint: str, n: int, out: str) -> None:
    with Node(BusConfig(connect=(endpoint,)), "t1", "test_subscriber") as node:
        sub = node.subscriber("vehicle_command", capacity=n + 16)
        got = []
        while len(got) < n:
            item = sub.recv()
            t, pub, seq, msg = item.time_us, item.publisher, item.seq, item.msg
            got.append({"t": t, "publisher": pub, "seq": seq, "param1": msg.param1, "command": msg.command})
    with open(out, "w") as f:
        json.dump(got, f)


def rogue() -> None:
    vehicle, bus = find_stack(None, None)
    with zenoh.open(bus.zenoh_config("rogue")) as session:
        key = keys.topic_key(vehicle, "vehicle_command", 0)
        pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
        wait_matching(pub)
        good_fp = fingerprint(VehicleCommand)
        for i in range(20):
            # The right header with a payload that is not a VehicleCommand.
            pub.put(b"\xc1\x00garbage", attachment=HEADER.pack(good_fp, 99, i, i + 1, 0, 0, 0))
            # A well-formed message from a publisher built with another definition.
            foreign = HEADER.pack(good_fp ^ 1, 99, i, i + 1, 0, 0, 0)
            pub.put(msgspec.msgpack.encode(VehicleCommand()), attachment=foreign)
            # No stack header at all.
            pub.put(msgspec.msgpack.encode(VehicleCommand()))
            time.sleep(0.01)  # a sender's pace, not a burst
        time.sleep(FLUSH_S)
        pub.undeclare()


def attack(members: list[str]) -> None:
    vehicle, bus = find_stack(None, None)
    encode = msgspec.msgpack.encode
    with zenoh.open(bus.zenoh_config("attacker")) as session:
        wait_matching(session.declare_publisher(keys.topic_key(vehicle, "sensor_gyro", 0)))
        lockstep_keys = [keys.lockstep_ack_key(vehicle), keys.lockstep_clock_key(vehicle)]
        lockstep_keys += [keys.lockstep_tick_key(vehicle, m) for m in members]
        forged = [
            encode(LockstepClock(timestamp=10**12, run=12345, step=10**9, counts=[(1, "sensor_gyro/0", 10**9)])),
            encode(LockstepAck(timestamp=10**12, run=12345, member=members[0], publisher_id=1, trigger_topic="@timer")),
        ]
        for key in lockstep_keys:
            for i in range(10):
                session.put(key, b"\xc1garbage" * i)
            for payload in forged:
                session.put(key, payload)
        gyro = keys.topic_key(vehicle, "sensor_gyro", 0)
        simulator = stable_publisher_id(vehicle, "tick_source")
        fp = fingerprint(SensorGyro)
        session.put(
            gyro,
            encode(SensorGyro(timestamp=10**12, x=1e9)),
            attachment=HEADER.pack(fp, simulator, 1, 1, 10**12, FLAG_LOCKSTEP_TIME, 12345),
        )
        session.put(gyro, encode(SensorGyro(timestamp=1, x=1e9)), attachment=HEADER.pack(fp, 4242, 1, 1, 1, 0, 0))
        rates = keys.topic_key(vehicle, "vehicle_rates_setpoint", 0)
        rates_fp = fingerprint(VehicleRatesSetpoint)
        for i in range(1000):
            session.put(rates, b"\xc1garbage", attachment=HEADER.pack(rates_fp, 4242, i, i + 1, 0, 0, 0))
            if i % 100 == 0:
                time.sleep(0.1)  # a flood in bursts of 100
        time.sleep(FLUSH_S)


def forge() -> None:
    vehicle, bus = find_stack(None, None)
    alive = f"{keys.ROOT}/{vehicle}/@alive"
    malformed = [f"{alive}/commander/notanint", f"{alive}/commander/-1", f"{alive}/commander", f"{alive}/a/b/1"]
    with zenoh.open(bus.zenoh_config("forger")) as session:
        for _ in range(5):
            for key in malformed:
                session.liveliness().declare_token(key).undeclare()
        done = session.liveliness().declare_token(keys.alive_token(vehicle, "forge_done", 4242))
        time.sleep(FLUSH_S)
        done.undeclare()


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "pub":
        publish(sys.argv[2], int(sys.argv[3]))
    elif mode == "sub":
        subscribe(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    elif mode == "rogue":
        rogue()
    elif mode == "forge":
        forge()
    elif mode == "attack":
        attack(sys.argv[2:])
    else:
        sys.exit(f"unknown mode {mode}")
