"""Cost of the live Rerun plots: the bridge's CPU per second of flight, and its effect on lockstep speed.

Run with ``python benchmarks/bench_viz.py``.

1. FlightLogger alone, fed synthetic messages at the stack's default topic rates (250 Hz attitude,
   rates, setpoints, torque, thrust, motors, allocator status and ground truth; 83 Hz local
   position and its setpoint; 50 Hz trajectory setpoint; 20 Hz barometer; 10 Hz GPS; 2 Hz status),
   decoded from msgpack like the bridge does, flushed every 0.2 s of flight (the bridge flushes at
   5 Hz wall: this is its real-time case) into an .rrd file. It prints the CPU time (all threads,
   Rerun's included) per second of flight at the default plot rate (50 Hz) and at full rate.
2. A lockstep stack run with and without a ``rerun_bridge`` (saving to a file; no viewer): the
   real-time factor (simulated seconds per wall second, fitted to the lockstep coordinator's
   heartbeats) and the bridge process's CPU (Zenoh's receive threads included) per simulated
   second. The profile is ``launch/sitl_quad.toml`` when it exists, else the test chain of
   tests/support (a clock source and three small modules). Runs alternate with and without the
   bridge; medians are reported. Aim: the bridge slows lockstep by ≤ 10 %. The machine must be
   otherwise idle: on two shared cores, other work moves the RTF by more than that.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import msgspec
import psutil
import zenoh

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from stack.bus.config import BusConfig  # noqa: E402
from stack.bus.keys import heartbeat_all  # noqa: E402
from stack.bus.node import Node  # noqa: E402
from stack.bus.supervisors import vehicle_status  # noqa: E402
from stack.mathlib.quaternion import from_euler  # noqa: E402
from stack.msg import actuators, estimation, sensors, setpoints, simulation, system  # noqa: E402
from stack.msg.internal import ModuleHeartbeat  # noqa: E402
from tests.support.harness import RunningStack, chain_profile, wait_no_processes  # noqa: E402

MOTORS = (0.5,) * 4 + (math.nan,) * 8

# topic → (rate Hz, message factory of the step k and time t µs)
TOPIC_RATES = {
    "sim_groundtruth": (250.0, lambda k, t: simulation.SimGroundtruth(timestamp=t, position=(0.01 * k, 0.0, -5.0))),
    "vehicle_attitude": (250.0, lambda k, t: estimation.VehicleAttitude(timestamp=t, q=from_euler(0.01, 0.02, 0.3))),
    "vehicle_attitude_setpoint": (250.0, lambda k, t: setpoints.VehicleAttitudeSetpoint(timestamp=t)),
    "vehicle_angular_velocity": (250.0, lambda k, t: estimation.VehicleAngularVelocity(timestamp=t)),
    "vehicle_rates_setpoint": (250.0, lambda k, t: setpoints.VehicleRatesSetpoint(timestamp=t)),
    "vehicle_torque_setpoint": (250.0, lambda k, t: setpoints.VehicleTorqueSetpoint(timestamp=t)),
    "vehicle_thrust_setpoint": (250.0, lambda k, t: setpoints.VehicleThrustSetpoint(timestamp=t)),
    "actuator_motors": (
        250.0,
        lambda k, t: actuators.ActuatorMotors(timestamp=t, control=(0.5,) * 4 + (math.nan,) * 8),
    ),
    "actuator_outputs_sim": (250.0, lambda k, t: actuators.ActuatorOutputs(timestamp=t, noutputs=4)),
    "control_allocator_status": (250.0, lambda k, t: actuators.ControlAllocatorStatus(timestamp=t)),
    "vehicle_local_position": (250.0 / 3, lambda k, t: estimation.VehicleLocalPosition(timestamp=t, x=0.01 * k)),
    "vehicle_local_position_setpoint": (250.0 / 3, lambda k, t: setpoints.VehicleLocalPositionSetpoint(timestamp=t)),
    "trajectory_setpoint": (50.0, lambda k, t: setpoints.TrajectorySetpoint(timestamp=t, position=(5.0, 0.0, -5.0))),
    "sensor_baro": (20.0, lambda k, t: sensors.SensorBaro(timestamp=t, pressure=101000.0)),
    "sensor_gps": (10.0, lambda k, t: sensors.SensorGps(timestamp=t, latitude_deg=47.0)),
    "vehicle_status": (2.0, lambda k, t: system.VehicleStatus(timestamp=t)),
}


def synthetic_flight(seconds: float) -> list[tuple[str, type, bytes]]:
    """(topic, type, msgpack payload) in time order, at the rates above, from a 250 Hz step clock."""
    encoder = msgspec.msgpack.Encoder()
    out = []
    for k in range(1, round(seconds * 250) + 1):
        t = 4000 * k
        for topic, (rate, make) in TOPIC_RATES.items():
            every = round(250.0 / rate)
            if k % every == 0:
                msg = make(k, t)
                out.append((topic, type(msg), encoder.encode(msg)))
    return out


def bench_logger(seconds: float, plot_rate_hz: float, out: Path) -> dict[str, float]:
    from stack.viz.layout import default_blueprint
    from stack.viz.logger import FlightLogger, new_recording

    flight = synthetic_flight(seconds)
    decoders = {t: msgspec.msgpack.Decoder(cls) for t, cls, _ in flight}
    rec = new_recording("bench")
    rec.save(out, default_blueprint=default_blueprint())
    logger = FlightLogger(rec, plot_rate_hz=plot_rate_hz, flush_period_s=0.2)
    wall = time.time_ns() // 1000
    log_message = logger.log_message
    cpu0 = time.process_time()
    for topic, _, payload in flight:
        log_message(topic, 0, decoders[topic].decode(payload), wall)
    logger.flush()
    rec.flush()
    cpu = time.process_time() - cpu0
    rec.disconnect()
    return {
        "messages_per_s": len(flight) / seconds,
        "cpu_ms_per_flight_s": cpu / seconds * 1e3,
        "us_per_message": cpu / len(flight) * 1e6,
        "chunks_per_s": logger.chunks_sent / seconds,
        "kept_per_s": logger.kept / seconds,
    }


def profile_with_bridge(base: Path, out_dir: Path, bridge: bool) -> Path:
    text = base.read_text()
    if bridge:
        rrd = out_dir / "bench_plots.rrd"
        text += (
            f'\n[[module]]\nname = "bench_plots"\nmodule = "rerun_bridge"\nargs = {{ save = "{rrd}", spawn = false }}\n'
        )
    path = out_dir / f"{base.stem}{'_plot' if bridge else ''}.toml"
    path.write_text(text)
    return path


def slope(points: list[tuple[float, float]]) -> float:
    """Least-squares slope of y over x."""
    mx = statistics.fmean(x for x, _ in points)
    my = statistics.fmean(y for _, y in points)
    return sum((x - mx) * (y - my) for x, y in points) / sum((x - mx) ** 2 for x, _ in points)


def measure_rtf(profile: Path, home: Path, warmup_s: float, window_s: float) -> tuple[float, float]:
    """(real-time factor, bridge CPU seconds per simulated second or NaN) over ``window_s`` of wall time.

    The simulated clock is read from the lockstep coordinator's heartbeats (about 1 Hz, so reading
    them adds no load), each paired with its arrival time; the RTF is the slope of the fit.
    """
    decoder = msgspec.msgpack.Decoder(ModuleHeartbeat)
    beats: list[tuple[float, float]] = []
    measuring = threading.Event()

    def on_heartbeat(sample: zenoh.Sample) -> None:
        hb = decoder.decode(sample.payload.to_bytes())
        if measuring.is_set() and hb.trigger == "lockstep coordinator":
            beats.append((time.monotonic(), hb.sim_time_us / 1e6))

    stack = RunningStack(home, profile, "--quiet")
    try:
        stack.wait_up(timeout=120)
        found = stack_state(home)
        bus = BusConfig(mode="client", connect=(str(found["endpoint"]),), listen=())
        with Node(bus, str(found["vehicle"]), "bench", stable_id=False) as node:
            sub = node.session.declare_subscriber(heartbeat_all(node.vehicle), on_heartbeat)
            status = vehicle_status(node.session, node.vehicle)
            pids = {m["module"]: m["pid"] for m in status["modules"]}
            bridge = psutil.Process(pids["bench_plots"]) if "bench_plots" in pids else None
            time.sleep(warmup_s)
            c0 = sum(bridge.cpu_times()[:2]) if bridge else 0.0
            measuring.set()
            time.sleep(window_s)
            measuring.clear()
            c1 = sum(bridge.cpu_times()[:2]) if bridge else 0.0
            sub.undeclare()
    finally:
        stack.stop()
        stack.kill()
    wait_no_processes(home)
    rtf = slope(beats)
    return rtf, ((c1 - c0) / (rtf * window_s) if bridge else math.nan)


def stack_state(home: Path) -> dict:
    """The state file `stack up` wrote for the stack running from ``home`` (vehicle, bus endpoint)."""
    (path,) = (home / "state").glob("*.json")
    return json.loads(path.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="synthetic flight length for part 1")
    parser.add_argument("--runs", type=int, default=3, help="stack runs with and without the bridge (part 2)")
    parser.add_argument("--window", type=float, default=10.0, help="wall seconds measured per stack run")
    parser.add_argument("--warmup", type=float, default=2.0, help="wall seconds skipped after the stack is up")
    parser.add_argument("--profile", default="", help="launch profile for part 2 (default: sitl_quad or the chain)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="bench_viz_") as tmp:
        tmp_dir = Path(tmp)
        print(f"1. FlightLogger, synthetic {args.seconds:g} s flight at the default topic rates, file sink")
        for rate in (50.0, 0.0):
            r = bench_logger(args.seconds, rate, tmp_dir / f"logger_{rate:g}.rrd")
            label = f"plot rate {rate:g} Hz" if rate else "full rate"
            print(
                f"   {label:<16} {r['messages_per_s']:7.0f} msg/s in, {r['kept_per_s']:6.0f} drawn/s, "
                f"{r['chunks_per_s']:5.0f} entity chunks/s: {r['cpu_ms_per_flight_s']:6.1f} ms CPU per "
                f"second of flight ({r['us_per_message']:.2f} µs/message, decode included)"
            )

        default = REPO / "launch" / "sitl_quad.toml"
        if args.profile:
            base = Path(args.profile)
        elif default.exists():
            base = default
        else:
            base = chain_profile(tmp_dir / "chain.toml")
        print(f"2. lockstep real-time factor with and without the bridge ({base.name}, {args.runs} runs each)")
        without: list[float] = []
        with_bridge: list[float] = []
        cpu: list[float] = []
        for i in range(args.runs):
            for bridge in (False, True):
                profile = profile_with_bridge(base, tmp_dir, bridge)
                rtf, bridge_cpu = measure_rtf(profile, tmp_dir / f"home_{i}_{bridge}", args.warmup, args.window)
                (with_bridge if bridge else without).append(rtf)
                if bridge:
                    cpu.append(bridge_cpu)
                print(f"   run {i + 1} {'with' if bridge else 'without':<7} bridge: RTF {rtf:5.2f}")
        a, b = statistics.median(without), statistics.median(with_bridge)
        print(f"   median RTF without {a:.2f}, with {b:.2f}: {100 * (1 - b / a):+.1f} % slower with the bridge")
        print(f"   bridge process CPU: {1e3 * statistics.median(cpu):.1f} ms per simulated second")


if __name__ == "__main__":
    main()
