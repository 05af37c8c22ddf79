"""Bus latency and throughput between two processes on loopback: the stack bus, raw Zenoh, a Unix socket.

Run with ``python benchmarks/bench_bus.py`` (``--quick`` for a few-second check). For each transport
a "ping" and a "pong" process (fresh interpreters, started by this script, which opens no session
itself) measure, in this order:

1. round trips: ping sends a message, pong sends it back, ping waits for it; ``--count`` of them
   after ``--warmup``. The one-way figure is the ping→pong leg (both processes read CLOCK_MONOTONIC);
2. throughput: ping sends ``--messages`` small and ``--large-messages`` ~1 kB messages one way as
   fast as the transport takes them; the rate is messages received over the time from the first
   send to the last receipt, and the loss is what never arrived.

Transports:

- ``stack``: :class:`stack.bus.node.Node` publishers and subscribers (33-byte header, msgspec, schema
  check), ``sensor_gyro`` messages (~100 B with the header), the lockstep runtime's subscriber
  queue; sessions from ``BusConfig`` defaults like a stack's modules: peer mode, each process
  listening on its own 127.0.0.1 endpoint, the second connecting to the first, no scouting,
  low-latency transport.
- ``raw``: zenoh-python ``put`` and a FIFO channel subscriber on the same session configuration,
  with payloads of the stack's wire size (message + header).
- ``uds``: a ``SOCK_SEQPACKET`` Unix-domain socket with the same payloads: the floor.

Publishers block under congestion (the stack's setting for everything but telemetry); ``--drop``
uses DROP (the telemetry setting) for the throughput runs, where losses can then appear.

On a small VM the figures depend mostly on where the kernel puts the two processes: waking a
process on the other vCPU costs tens of µs, switching to it on the same vCPU a few. ``--cpus same``
or ``--cpus split`` pins them (both on one CPU, or one each) to measure either case.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from importlib.metadata import version
from pathlib import Path

import zenoh
from msgspec.msgpack import encode

from stack.bus.config import BusConfig
from stack.bus.node import Node, wall_clock_us
from stack.bus.ports import free_port
from stack.bus.topics import HEADER
from stack.msg.base import Message
from stack.msg.registry import register_topic
from stack.msg.sensors import SensorGyro
from stack.runtime.runner import LOCKSTEP_QUEUE

PROBE_BASE = -2000  # handshake probes count down from PROBE_BASE; end markers are END_BASE - phase
END_BASE = -1000
CHANNELS = ("ping", "pong", "small", "large")
STACK_TOPICS = {
    "ping": ("sensor_gyro", 0),
    "pong": ("sensor_gyro", 1),
    "small": ("sensor_gyro", 2),
    "large": ("bench_payload", 0),
}
SEQ_OFFSET = 1 << 33  # sequence numbers as µs-sized integers, so every stack message has the same size


class BenchPayload(Message):
    """A bench-only topic of adjustable size (``data`` pads it to about 1 kB)."""

    timestamp_sample: int = 0
    data: bytes = b""


register_topic("bench_payload", BenchPayload)


def gyro(sample: int) -> SensorGyro:
    return SensorGyro(timestamp_sample=sample, device_id=1310988, x=0.01, y=-0.02, z=0.03, temperature=15.0)


def stack_sizes(large: int) -> tuple[int, int, int]:
    """Wire bytes (payload + header) of a small and a large stack message, and the large message's padding."""
    now = wall_clock_us()
    small = gyro(SEQ_OFFSET)
    small.timestamp = now
    pad = large
    for _ in range(2):  # the length prefix of ``data`` depends on its length
        size = len(encode(BenchPayload(timestamp=now, timestamp_sample=SEQ_OFFSET, data=bytes(pad)))) + HEADER.size
        pad = max(pad - (size - large), 0)
    return len(encode(small)) + HEADER.size, size, pad


# -- links: one interface over the three transports ------------------------------------------------


class StackLink:
    """Channels as stack topics (``STACK_TOPICS``); the sequence number rides in ``timestamp_sample``."""

    def __init__(self, bus: BusConfig, role: str, drop: bool, pad: int) -> None:
        self.node = Node(bus, "bench", role)
        self.blob = bytes(pad)
        outs = ("ping", "small", "large") if role == "ping" else ("pong",)
        self.pubs = {
            c: self.node.publisher(*STACK_TOPICS[c], reliable=not (drop and c in ("small", "large"))) for c in outs
        }
        self.subs = {
            c: self.node.subscriber(*STACK_TOPICS[c], capacity=LOCKSTEP_QUEUE) for c in CHANNELS if c not in outs
        }

    def send(self, channel: str, seq: int) -> None:
        if channel == "large":
            self.pubs[channel].publish(BenchPayload(timestamp_sample=seq + SEQ_OFFSET, data=self.blob))
        else:
            self.pubs[channel].publish(gyro(seq + SEQ_OFFSET))

    def recv(self, channel: str) -> int:
        return self.subs[channel].recv()[3].timestamp_sample - SEQ_OFFSET

    def poll(self, channel: str) -> int | None:
        item = self.subs[channel].poll()
        return None if item is None else item.msg.timestamp_sample - SEQ_OFFSET

    def matched(self) -> bool:
        return all(p.matching() for p in self.pubs.values())

    def close(self) -> None:
        self.node.close()


class RawLink:
    """Channels as plain Zenoh keys; the sequence number is the payload's first 8 bytes."""

    def __init__(self, bus: BusConfig, role: str, drop: bool, small: int, large: int) -> None:
        self.session = zenoh.open(bus.zenoh_config(role))
        self.sizes = {"ping": small, "pong": small, "small": small, "large": large}
        outs = ("ping", "small", "large") if role == "ping" else ("pong",)
        self.pubs = {
            c: self.session.declare_publisher(
                f"bench/raw/{c}",
                congestion_control=zenoh.CongestionControl.DROP
                if drop and c in ("small", "large")
                else zenoh.CongestionControl.BLOCK,
                express=True,
            )
            for c in outs
        }
        self.subs = {
            c: self.session.declare_subscriber(f"bench/raw/{c}", zenoh.handlers.FifoChannel(LOCKSTEP_QUEUE))
            for c in CHANNELS
            if c not in outs
        }

    def send(self, channel: str, seq: int) -> None:
        self.pubs[channel].put(seq.to_bytes(8, "little", signed=True) + bytes(self.sizes[channel] - 8))

    def recv(self, channel: str) -> int:
        return int.from_bytes(self.subs[channel].recv().payload.to_bytes()[:8], "little", signed=True)

    def poll(self, channel: str) -> int | None:
        sample = self.subs[channel].try_recv()
        return None if sample is None else int.from_bytes(sample.payload.to_bytes()[:8], "little", signed=True)

    def matched(self) -> bool:
        return all(p.matching_status.matching for p in self.pubs.values())

    def close(self) -> None:
        self.session.close()


class UdsLink:
    """One SOCK_SEQPACKET connection carries every channel (the phases keep them apart)."""

    def __init__(self, path: str, role: str, small: int, large: int, on_listening: Callable[[], None]) -> None:
        self.sizes = {"ping": small, "pong": small, "small": small, "large": large}
        if role == "pong":
            with socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET) as server:
                server.bind(path)
                server.listen(1)
                on_listening()
                self.sock, _ = server.accept()
        else:
            self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            self.sock.connect(path)

    def send(self, channel: str, seq: int) -> None:
        self.sock.send(seq.to_bytes(8, "little", signed=True) + bytes(self.sizes[channel] - 8))

    def recv(self, channel: str) -> int:
        return int.from_bytes(self.sock.recv(65536)[:8], "little", signed=True)

    def poll(self, channel: str) -> int | None:
        try:
            data = self.sock.recv(65536, socket.MSG_DONTWAIT)
        except BlockingIOError:
            return None
        return int.from_bytes(data[:8], "little", signed=True)

    def matched(self) -> bool:
        return True

    def close(self) -> None:
        self.sock.close()


Link = StackLink | RawLink | UdsLink


def wait_for(link: Link, channel: str, wanted: int, timeout: float) -> bool:
    """Poll for ``wanted`` (other values are dropped) for at most ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        seq = link.poll(channel)
        if seq == wanted:
            return True
        if seq is None:
            time.sleep(0.0005)
    return False


# -- the two roles ---------------------------------------------------------------------------------


def run_ping(link: Link, args: argparse.Namespace) -> dict:
    deadline = time.monotonic() + 20.0
    while not link.matched():
        if time.monotonic() > deadline:
            raise SystemExit("ping: the pong process's subscribers never matched")
        time.sleep(0.005)
    probe = PROBE_BASE
    link.send("ping", probe)
    while not wait_for(link, "pong", probe, 0.05):  # the return path is up once a probe comes back
        if time.monotonic() > deadline:
            raise SystemExit("ping: no probe came back")
        probe -= 1
        link.send("ping", probe)
    send_ns: list[int] = []
    rtt_ns: list[int] = []
    clock = time.monotonic_ns
    for i in range(args.warmup + args.count):
        t0 = clock()
        link.send("ping", i)
        while link.recv("pong") != i:
            pass
        t1 = clock()
        if i >= args.warmup:
            send_ns.append(t0)
            rtt_ns.append(t1 - t0)
    finish(link, "ping", 0)
    starts = []
    for phase, (channel, n) in enumerate((("small", args.messages), ("large", args.large_messages)), start=1):
        t0 = clock()
        for i in range(n):
            link.send(channel, i)
        starts.append(t0)
        finish(link, channel, phase)
    return {"send_ns": send_ns, "rtt_ns": rtt_ns, "starts_ns": starts}


def finish(link: Link, channel: str, phase: int) -> None:
    """Send the phase's end marker until the pong acknowledges it."""
    end = END_BASE - phase
    for _ in range(60):
        link.send(channel, end)
        if wait_for(link, "pong", end, 1.0):
            return
    raise SystemExit(f"ping: phase {phase} was never acknowledged")


def run_pong(link: Link, args: argparse.Namespace) -> dict:
    clock = time.monotonic_ns
    recv_ns: dict[int, int] = {}
    while True:
        seq = link.recv("ping")
        t = clock()
        link.send("pong", seq)
        if seq == END_BASE:
            break
        if seq >= 0:
            recv_ns[seq] = t
    sinks = []
    for phase, (channel, n) in enumerate((("small", args.messages), ("large", args.large_messages)), start=1):
        seen = bytearray(n)
        first = last = 0
        while True:
            seq = link.recv(channel)
            if seq == END_BASE - phase:
                link.send("pong", seq)
                break
            if 0 <= seq < n:
                last = clock()
                first = first or last
                seen[seq] = 1
        sinks.append({"received": sum(seen), "first_ns": first, "last_ns": last})
    return {"recv_ns": [recv_ns.get(i, 0) for i in range(args.warmup, args.warmup + args.count)], "sinks": sinks}


def ready() -> None:
    print("ready", flush=True)


def child(args: argparse.Namespace) -> None:
    if args.cpus != "any":  # before any thread starts, so Zenoh's threads inherit it
        cpus = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpus[0] if args.cpus == "same" or args.role == "ping" else cpus[-1]})
    small, large, pad = stack_sizes(args.large_size)
    link: Link
    if args.transport == "uds":
        link = UdsLink(args.uds_path, args.role, small, large, ready)
    else:
        me, peer = (args.ping_port, args.pong_port) if args.role == "ping" else (args.pong_port, args.ping_port)
        bus = BusConfig(
            listen=(f"tcp/127.0.0.1:{me}",), connect=(f"tcp/127.0.0.1:{peer}",) if args.role == "ping" else ()
        )
        if args.transport == "stack":
            link = StackLink(bus, args.role, args.drop, pad)
        else:
            link = RawLink(bus, args.role, args.drop, small, large)
        if args.role == "pong":
            ready()
    try:
        result = run_ping(link, args) if args.role == "ping" else run_pong(link, args)
    finally:
        link.close()
    print(json.dumps(result), flush=True)


# -- the orchestrator --------------------------------------------------------------------------------


def measure(transport: str, args: argparse.Namespace, common: list[str]) -> dict:
    with tempfile.TemporaryDirectory(prefix="bench_bus") as tmp:
        extra = [
            "--transport",
            transport,
            "--uds-path",
            str(Path(tmp) / "s"),
            "--ping-port",
            str(free_port()),
            "--pong-port",
            str(free_port()),
        ]
        cmd = [sys.executable, __file__, *common, *extra]
        pong = subprocess.Popen([*cmd, "--role", "pong"], stdout=subprocess.PIPE, text=True)
        ping: subprocess.Popen | None = None
        try:
            assert pong.stdout is not None
            if pong.stdout.readline().strip() != "ready":
                raise SystemExit(f"{transport}: the pong process did not start")
            ping = subprocess.Popen([*cmd, "--role", "ping"], stdout=subprocess.PIPE, text=True)
            ping_out, _ = ping.communicate(timeout=args.timeout)
            pong_out, _ = pong.communicate(timeout=args.timeout)
        finally:
            for p in (ping, pong):
                if p is not None and p.poll() is None:
                    p.kill()
                    p.wait()
    if ping.returncode or pong.returncode:
        raise SystemExit(f"{transport}: ping exited with {ping.returncode}, pong with {pong.returncode}")
    a, b = json.loads(ping_out.splitlines()[-1]), json.loads(pong_out.splitlines()[-1])
    one_way = [r - s for s, r in zip(a["send_ns"], b["recv_ns"], strict=True) if r]
    rates = []
    for start, sink, n in zip(a["starts_ns"], b["sinks"], (args.messages, args.large_messages), strict=True):
        span = (sink["last_ns"] - start) * 1e-9
        rates.append((sink["received"] / span if span > 0 else 0.0, n - sink["received"]))
    return {"rtt": sorted(a["rtt_ns"]), "one_way": sorted(one_way), "rates": rates}


def pct(sorted_ns: list[int], q: float) -> float:
    """The q-quantile in µs (nearest rank)."""
    return sorted_ns[min(len(sorted_ns) - 1, int(q * len(sorted_ns)))] / 1000.0


NAMES = {"stack": "stack bus", "raw": "raw zenoh", "uds": "unix socket"}


def report(results: dict[str, dict], args: argparse.Namespace) -> None:
    small, large, _ = stack_sizes(args.large_size)
    print(f"\nround trips: {args.count} after {args.warmup} warm-up, {small} B messages (µs)")
    print(f"{'transport':<12} {'p50':>7} {'p90':>7} {'p99':>7} {'max':>8} {'1-way p50':>10} {'1-way p99':>10}")
    for t, r in results.items():
        rtt, ow = r["rtt"], r["one_way"]
        print(
            f"{NAMES[t]:<12} {pct(rtt, 0.5):>7.1f} {pct(rtt, 0.9):>7.1f} {pct(rtt, 0.99):>7.1f} {rtt[-1] / 1e3:>8.1f}"
            f" {pct(ow, 0.5):>10.1f} {pct(ow, 0.99):>10.1f}"
        )
    mode = "DROP" if args.drop else "BLOCK"
    print(f"\nthroughput one way, unthrottled ({mode}): messages/s (lost)")
    print(f"{'transport':<12} {f'{small} B x {args.messages}':>22} {f'{large} B x {args.large_messages}':>22}")
    for t, r in results.items():
        cells = [f"{rate:>14,.0f} ({lost})" for rate, lost in r["rates"]]
        print(f"{NAMES[t]:<12} {cells[0]:>22} {cells[1]:>22}")
    if "stack" in results and "raw" in results:
        s, w = results["stack"], results["raw"]
        print(
            f"\nstack/raw: RTT p50 x{pct(s['rtt'], 0.5) / pct(w['rtt'], 0.5):.2f}, p99 x"
            f"{pct(s['rtt'], 0.99) / pct(w['rtt'], 0.99):.2f}; throughput x{s['rates'][0][0] / w['rates'][0][0]:.2f}"
            f" (small), x{s['rates'][1][0] / w['rates'][1][0]:.2f} (1 kB)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5000, help="measured round trips")
    parser.add_argument("--warmup", type=int, default=500, help="round trips before measuring")
    parser.add_argument("--messages", type=int, default=100_000, help="small messages for the throughput run")
    parser.add_argument("--large-messages", type=int, default=20_000, help="large messages for the throughput run")
    parser.add_argument("--large-size", type=int, default=1024, help="wire bytes of a large message")
    parser.add_argument("--transports", nargs="+", choices=list(NAMES), default=list(NAMES))
    parser.add_argument("--drop", action="store_true", help="DROP instead of BLOCK congestion control for throughput")
    parser.add_argument(
        "--cpus",
        choices=("any", "same", "split"),
        default="any",
        help="where the two processes run: as the kernel places them, both on one CPU, or one CPU each",
    )
    parser.add_argument("--quick", action="store_true", help="small counts: a few seconds in all")
    parser.add_argument("--timeout", type=float, default=300.0, help="give up on a transport after this long (s)")
    parser.add_argument("--role", choices=("ping", "pong"), help=argparse.SUPPRESS)
    parser.add_argument("--transport", choices=list(NAMES), help=argparse.SUPPRESS)
    parser.add_argument("--uds-path", help=argparse.SUPPRESS)
    parser.add_argument("--ping-port", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--pong-port", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.quick:
        args.count, args.warmup, args.messages, args.large_messages = 1000, 200, 10_000, 3_000
    if args.role:
        child(args)
        return
    common = [
        "--count",
        str(args.count),
        "--warmup",
        str(args.warmup),
        "--messages",
        str(args.messages),
        "--large-messages",
        str(args.large_messages),
        "--large-size",
        str(args.large_size),
        *(["--drop"] if args.drop else []),
        *("--cpus", args.cpus),
    ]
    load = os.getloadavg()
    print(
        f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs, "
        f"eclipse-zenoh {version('eclipse-zenoh')}, Python {sys.version.split()[0]}"
    )
    results = {}
    for t in args.transports:
        start = time.monotonic()
        results[t] = measure(t, args, common)
        print(f"{NAMES[t]}: measured in {time.monotonic() - start:.1f} s", flush=True)
    report(results, args)


if __name__ == "__main__":
    main()
