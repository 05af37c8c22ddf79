"""Flight recorder throughput: messages per second written, and CPU for a typical stack's traffic.

Run with ``python benchmarks/bench_record.py``. Three figures, each the best of ``--repeat`` runs:

1. ``JsonMessageCodec.encode`` per message type (µs per message);
2. ``RecordingWriter.write`` on a typical stack's message mix (JSON + mcap chunking + zstd), in
   messages per second of one core;
3. end to end: a publisher process sends the mix through Zenoh as fast as the bus takes it, and
   the recorder's subscriber, ``SampleRecorder`` and writer thread (exactly the module's path)
   record it; reported as messages per second and CPU µs per message of the recording process
   (Zenoh's receive threads included), and what that CPU means for the typical stack at 1× and 5×
   real time.

The typical mix (~3,550 messages per simulated second) assumes the PX4-shaped stack's rates: 250 Hz
IMU, rate loop and actuator topics, 100 Hz estimator and position-loop topics, 50/20/10 Hz mag,
baro and GPS, 2 Hz status topics. The recorder must keep up with ≥5× real time in lockstep, i.e.
~18,000 messages/s, on a shared 2-core machine.
"""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import os
import tempfile
import time
from pathlib import Path

import zenoh

from stack.bus.config import BusConfig
from stack.bus.node import Node
from stack.msg.registry import TOPICS
from stack.record.jsoncodec import codec_for
from stack.record.module import QUEUE_CAPACITY, RecordingPump, SampleRecorder
from stack.record.recorder import RecordingWriter, new_recording_info
from stack.record.selection import TopicSelection

MIX_HZ: dict[str, float] = {
    **dict.fromkeys(
        (
            "sensor_gyro",
            "sensor_accel",
            "vehicle_angular_velocity",
            "vehicle_attitude",
            "vehicle_rates_setpoint",
            "vehicle_torque_setpoint",
            "vehicle_thrust_setpoint",
            "actuator_motors",
            "actuator_outputs_sim",
            "sim_groundtruth",
            "control_allocator_status",
            "rate_ctrl_status",
        ),
        250.0,
    ),
    **dict.fromkeys(
        (
            "vehicle_local_position",
            "vehicle_attitude_setpoint",
            "trajectory_setpoint",
            "vehicle_local_position_setpoint",
        ),
        100.0,
    ),
    "sensor_mag": 50.0,
    "vehicle_global_position": 50.0,
    "sensor_baro": 20.0,
    "sensor_gps": 10.0,
    "vehicle_gps_position": 10.0,
    "vehicle_status": 2.0,
    "vehicle_control_mode": 2.0,
    "actuator_armed": 2.0,
}
MIX_PER_SECOND = sum(MIX_HZ.values())
ENDPOINT = "tcp/127.0.0.1:17491"
VEHICLE = "bench"


def mix_schedule(seconds: float) -> list[tuple[str, int]]:
    """(topic, timestamp µs) in time order, for ``seconds`` of simulated flight at 4 ms steps."""
    out: list[tuple[str, int]] = []
    periods = {t: round(1e6 / hz) for t, hz in MIX_HZ.items()}
    for step in range(round(seconds * 250)):
        t = step * 4000
        out += [(topic, t) for topic, period in periods.items() if t % period < 4000]
    return out


def sample_message(topic: str, t: int) -> object:
    msg_type = TOPICS[topic]
    fields = {"timestamp": t}
    if "timestamp_sample" in msg_type.__struct_fields__:
        fields["timestamp_sample"] = t
    if topic == "sim_groundtruth":
        fields["motors"] = (0.5, 0.5, 0.5, 0.5)
    return msg_type(**fields)


def bench_encode(repeat: int) -> None:
    print("JSON encoding (µs per message):")
    for name in sorted({t.__name__: t for t in TOPICS.values()}):
        msg_type = next(t for t in TOPICS.values() if t.__name__ == name)
        codec = codec_for(msg_type)
        msg = msg_type()
        batch = [msg] * 20_000
        best = min(_timed(lambda codec=codec, batch=batch: [codec.encode(m) for m in batch]) for _ in range(repeat))
        print(f"  {name:28s} {best / len(batch) * 1e6:6.2f}")


def _timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def bench_writer(seconds: float, repeat: int) -> float:
    schedule = mix_schedule(seconds)
    messages = [(topic, sample_message(topic, t), t) for topic, t in schedule]
    rates = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeat):
            path = Path(tmp) / "bench.mcap"
            writer = RecordingWriter(path, new_recording_info(VEHICLE, "bench", 1, True, ""))
            start = time.perf_counter()
            for seq, (topic, msg, t) in enumerate(messages, 1):
                writer.write(topic, 0, msg, 0x1234, seq, t, 1, t)
            writer.close()
            rates.append(len(messages) / (time.perf_counter() - start))
            size = path.stat().st_size
    best = max(rates)
    print(
        f"RecordingWriter.write: {best:,.0f} messages/s ({1e6 / best:.2f} µs per message), "
        f"{size / len(messages):.1f} bytes per message on disk"
    )
    return best


def _publisher(seconds: float, ready: multiprocessing.Event) -> None:
    schedule = mix_schedule(seconds)
    with Node(BusConfig(listen=(ENDPOINT,)), VEHICLE, "bench_publisher") as node:
        pubs = {topic: node.publisher(topic, reliable=True) for topic in MIX_HZ}
        messages = [(pubs[topic], sample_message(topic, t), t) for topic, t in schedule]
        deadline = time.monotonic() + 10.0
        while not all(p.matching() for p in pubs.values()) and time.monotonic() < deadline:
            time.sleep(0.01)
        ready.set()
        for pub, msg, t in messages:
            pub.publish(msg, t)
        time.sleep(1.0)


def bench_end_to_end(seconds: float) -> tuple[float, float]:
    n = len(mix_schedule(seconds))
    ctx = multiprocessing.get_context("spawn")
    ready = ctx.Event()
    proc = ctx.Process(target=_publisher, args=(seconds, ready))
    bus = BusConfig(connect=(ENDPOINT,), listen=())
    with tempfile.TemporaryDirectory() as tmp, zenoh.open(bus.zenoh_config("bench_recorder")) as session:
        writer = RecordingWriter(Path(tmp) / "e2e.mcap", new_recording_info(VEHICLE, "bench", 1, True, ""))
        sink = SampleRecorder(writer, TopicSelection(), lockstep=True)
        sub = session.declare_subscriber(f"stack/{VEHICLE}/*/*", zenoh.handlers.FifoChannel(QUEUE_CAPACITY))
        pump = RecordingPump(sub, sink, _quiet_logger())
        proc.start()
        ready.wait(30.0)
        cpu0 = os.times()
        start = time.perf_counter()
        pump.start()
        while writer.messages < n and proc.is_alive():
            time.sleep(0.001)
        elapsed = time.perf_counter() - start
        cpu1 = os.times()
        pump.stop()
        sub.undeclare()
        proc.join(10.0)
    cpu = (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system)
    rate = writer.messages / elapsed
    per_msg = cpu / max(writer.messages, 1)
    print(
        f"end to end: {writer.messages}/{n} messages at {rate:,.0f} messages/s, "
        f"{per_msg * 1e6:.1f} µs CPU per message (recording process, Zenoh threads included)"
    )
    for factor in (1, 5):
        load = MIX_PER_SECOND * factor
        print(f"  typical stack at {factor}x real time ({load:,.0f} msg/s): {load * per_msg * 100:.0f} % of one core")
    return rate, per_msg


def _quiet_logger() -> logging.Logger:
    log = logging.getLogger("bench.recorder")
    log.addHandler(logging.NullHandler())
    log.propagate = False
    return log


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="Simulated seconds of traffic per run")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"typical mix: {MIX_PER_SECOND:,.0f} messages per simulated second on {len(MIX_HZ)} topics")
    bench_encode(args.repeat)
    bench_writer(args.seconds, args.repeat)
    bench_end_to_end(args.seconds)


if __name__ == "__main__":
    main()
