"""How a topic reaches a host, measured on it: run there as ``python -m tests.hosts.arrivals TOPIC SECONDS``.

Every WINDOW_S it prints one JSON line: the messages received, the longest gap before an arrival, and their age
on arrival (the arrival time on this host's clock minus the message's timestamp; the test hosts share one clock)."""

from __future__ import annotations

import itertools
import json
import sys
import threading
import time

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.node import wall_clock_us
from stack.cli.common import connect, wait_until_sent
from stack.msg.registry import message_type

WINDOW_S = 1.0


def quantile(values: list[int], q: float) -> int:
    return sorted(values)[min(len(values) - 1, int(q * len(values)))] if values else 0


def window_figures(arrivals: list[tuple[int, int]], last: int | None) -> dict[str, float]:
    """Figures of one window's (arrival, timestamp) pairs [µs], ``last`` the arrival before them."""
    times = [t for t, _ in arrivals] if last is None else [last, *(t for t, _ in arrivals)]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    ages = [arrived - stamped for arrived, stamped in arrivals]
    return {
        "received": len(arrivals),
        "gap_max_s": max(gaps, default=0) / 1e6,
        "age_p50_s": quantile(ages, 0.5) / 1e6,
        "age_p99_s": quantile(ages, 0.99) / 1e6,
    }


def main(topic: str, seconds: float) -> None:
    decoder = msgspec.msgpack.Decoder(message_type(topic))
    arrivals: list[tuple[int, int]] = []
    lock = threading.Lock()

    def on_sample(sample: zenoh.Sample) -> None:
        arrived = wall_clock_us()
        try:
            stamped = decoder.decode(sample.payload.to_bytes()).timestamp
        except msgspec.DecodeError:
            return
        with lock:
            arrivals.append((arrived, stamped))

    with connect(None, None, "arrivals") as node:
        sub = node.session.declare_subscriber(keys.topic_key(node.vehicle, topic, 0), on_sample)
        node.announce("sub", topic, 0)
        wait_until_sent(node, [(topic, 0)])
        end = time.monotonic() + seconds
        last = None
        try:
            while time.monotonic() < end:
                time.sleep(WINDOW_S)
                with lock:
                    window, arrivals[:] = list(arrivals), []
                print(json.dumps(window_figures(window, last)), flush=True)
                last = window[-1][0] if window else last
        finally:
            sub.undeclare()


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]))
