"""A raw bus listener for replay tests: ``python -m tests.record.listener N OUT``.

Joins the running stack (found through STACK_HOME), subscribes to every topic of its vehicle,
prints "ready", and writes the first N samples (key, attachment, payload) to OUT as msgpack
(start-up probes, which carry no message, are skipped).
It uses Zenoh directly, not the recorder, so it checks replay independently of the code under test.
"""

import sys
import time

import msgspec
import zenoh

from stack.bus import keys
from stack.bus.topics import FLAG_PROBE, HEADER
from stack.cli.common import find_stack


def main(n: int, out: str) -> None:
    vehicle, bus = find_stack(None, None)
    got: list[tuple[str, bytes, bytes]] = []
    with zenoh.open(bus.zenoh_config("listener")) as session:
        sub = session.declare_subscriber(keys.all_topics(vehicle), zenoh.handlers.FifoChannel(1 << 16))
        time.sleep(0.3)
        print("ready", flush=True)
        deadline = time.monotonic() + 60.0
        while len(got) < n and time.monotonic() < deadline:
            sample = sub.try_recv()
            if sample is None:
                time.sleep(0.001)
                continue
            attachment = sample.attachment.to_bytes() if sample.attachment is not None else b""
            if len(attachment) == HEADER.size and HEADER.unpack(attachment)[5] & FLAG_PROBE:
                continue  # a publisher's start-up probe, not a message
            got.append((str(sample.key_expr), attachment, sample.payload.to_bytes()))
        sub.undeclare()
    with open(out, "wb") as f:
        f.write(msgspec.msgpack.encode(got))


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
